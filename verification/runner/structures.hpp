// The runner of case folders of kind `structure` (structures.cpp): a linear-elastic structure
// described by its folder's case.yaml, against the deal.II reference and beam/plate theory.
#pragma once

#include "libpd/io/scene.hpp"
#include "verification.hpp"

#include <filesystem>
#include <string>

namespace pd::verification {

/// The structure of ctx.folder/case.yaml at the paper's resolution, or (`fast`) at the case's CI
/// spacing with its regression and gates and no relaxation rerun.
Json run_structure_case(const Context& ctx, bool fast);
/// Its accuracy-vs-time sweep (`quick_sweep:` with ctx.quick where the file has one).
Json run_structure_sweep_case(const Context& ctx);
/// The `case:` name a structure case.yaml gives its runs (NAME, NAME-fast, NAME-sweep).
std::string structure_case_name(const std::filesystem::path& case_yaml);

/// A structural scene at another spacing (CI variants, sweeps, `pd compare quasistatic --quick`):
/// a load on the top particle layer stays on the top layer.
void set_spacing(Scene& scene, double spacing);

} // namespace pd::verification
