// The Griffith failure load of a cracked body from the FE compliance of that same body (issue 36).
// A handbook formula describes one idealised specimen (Feddersen's width factor: an infinitely
// long plate under uniform end stress); a scene's plate has its own height and grips, which move
// the failure load by a few per cent. Here deal.II solves the scene's elastic problem with the
// crack's tips moved by ±h, and the energy release rate at fixed grips,
//   G = −∂U/∂A = −(Δ/2) ∂P/∂A   (U = ½ P Δ, Δ the grips' opening, A the crack's area),
// scales with Δ², so the force at which G reaches G0 is P(a) √(G0 / G(a)): LEFM's failure load of
// exactly the body PD breaks.
#pragma once

#include "libpd/io/scene.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace pd::verification {

struct ComplianceGriffith {
  double failure_load = 0;         ///< extrapolated in the FE mesh size
  std::vector<double> level_loads; ///< the same on each FE level, coarse to fine
  double crack_step = 0;           ///< h: each tip moved by ±h
};

/// `scene_file` holds a crack (the scene's first, a segment) with one or two tips (ends inside a
/// body; an end on the surface is its mouth), opened by supports whose displacements differ by
/// `grip_opening` and read by the reaction probe `probe`. Runs pd-fem three times (crack as
/// given, each tip moved out and in by h, a tenth of the crack's length per tip) on
/// two mesh levels into `dir` and extrapolates the load to zero mesh size with order 1, the rate
/// at which the energy of a crack-tip field (u ~ √r) converges under uniform refinement.
ComplianceGriffith griffith_load_from_fe_compliance(const std::filesystem::path& scene_file,
                                                    const Scene& scene, const std::string& probe,
                                                    double grip_opening,
                                                    const std::filesystem::path& dir);

} // namespace pd::verification
