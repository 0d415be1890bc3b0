// The case functions registered in verification.cpp; one file per case under cases/.
#pragma once

#include "verification.hpp"

namespace pd::verification {

Json run_bond_count(const Context& ctx);
Json run_bar_vibration(const Context& ctx);
Json run_bar_energy(const Context& ctx);
Json run_block_tension(const Context& ctx);

} // namespace pd::verification
