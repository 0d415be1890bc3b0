// Output that survives interruption: every file is written to a temporary name and renamed into
// place, so a reader sees either the old file or the complete new one, never a truncated one.
// Non-finite numbers are never written (JSON gets null; VTU writing refuses).
#pragma once

#include "libpd/core/atomic_file.hpp"
#include "libpd/core/json.hpp"
#include "libpd/time/simulation.hpp"

#include <filesystem>
#include <limits>
#include <list>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace pd {

/// ParaView-readable VTU of the particles with displacement, velocity and (if present) damage as
/// point data. Throws if any value is not finite.
/// A run split over ranks writes the particles each rank owns; every file carries `global_id`,
/// the particle's index in the whole model, so that pieces join.
void write_vtu(const std::filesystem::path& path, const Simulation& sim);

/// The .pvtu file that joins VTU pieces written by write_vtu (file names relative to it).
std::string pvtu_text(const std::vector<std::string>& pieces, bool damage);

} // namespace pd
