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

/// A pair of grips: the reaction probe of one and the opening between them.
struct GripPair {
  std::string probe;
  double opening = 0;
};

/// The same where several pairs of grips load the body (a plate pulled both ways): at fixed
/// grips G = −½ Σ Δ_g ∂P_g/∂A, and the failure load returned is the first pair's, P_1(a) √(G0/G).
ComplianceGriffith griffith_load_from_fe_compliance(const std::filesystem::path& scene_file,
                                                    const Scene& scene,
                                                    const std::vector<GripPair>& grips,
                                                    const std::filesystem::path& dir);

/// LEFM's growth branch of the same body under a growing opening: at each crack length a0 + e
/// (e = 0, s, 2s, …, the tip moved by e), the load and grip opening at which G = G0, from the FE
/// compliance as above. dP/da is the fourth-order central difference on that grid (the tips
/// also moved by −2s, −s and past the last point; on the dcb case, s = h/4 and h/10 give
/// initiation loads 0.03 % apart); loads are extrapolated in the FE mesh size as above.
struct ComplianceGrowth {
  std::vector<double> extension; ///< e, of each tip
  std::vector<double> load;      ///< P at which G(a0 + e) = G0
  std::vector<double> opening;   ///< the grips' opening at that load
  /// LEFM's load at opening Δ on the growth branch (log–log interpolation between the points;
  /// NaN outside them).
  double load_at(double opening) const;
  /// LEFM's crack extension at opening Δ on the growth branch (NaN outside the points).
  double extension_at(double opening) const;
  /// The crack extension at which the compliance Δ / P (rising with the crack) is `compliance`,
  /// interpolated linearly (NaN outside the points).
  double extension_at_compliance(double compliance) const;
};

ComplianceGrowth lefm_growth_from_fe_compliance(const std::filesystem::path& scene_file,
                                                const Scene& scene, const std::string& probe,
                                                double grip_opening, double step,
                                                double max_extension,
                                                const std::filesystem::path& dir);

} // namespace pd::verification
