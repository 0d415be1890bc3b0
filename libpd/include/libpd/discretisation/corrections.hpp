// Per-bond correction factors: surface corrections (a particle near a free surface misses part of
// its horizon and is too soft) and partial-volume corrections (a neighbour whose cell is cut by the
// horizon sphere counts with only part of its volume). Both become one multiplicative factor per
// directed bond, folded into the bond stiffness once at set-up, so the force kernel only sees the
// per-bond field.
//
// All surface corrections here are geometric: they compare a particle's own (volume-corrected)
// bond sums with the sums of a full horizon, whatever the materials. A bond between two materials
// is therefore not treated as a free surface (Miranda §5.2 interfaces keep their own rule: the
// weaker material's constants, model.cpp).
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/physics/material.hpp"

#include <array>
#include <vector>

namespace pd {

/// Per-bond modifiers of the bond stiffness, beyond the neighbour volume (corrections.hpp).
enum class SurfaceCorrection { none, volume, energy, macek_silling, tensor, ghost };
/// Quadrature weights of the bonds: partial-volume corrections of neighbour cells cut by the
/// horizon (`linear`, `exact`), or lattice weights that reproduce the continuum's fourth moments
/// (`moment`) and also its strain-gradient energy (`gradient`), see below; or, for sets that are
/// not a lattice, weights fitted per pair to every particle's own neighbourhood (`fitted`), or
/// per-particle factors that give it the continuum's energies under uniaxial stress (`tensor`:
/// the tensor surface correction's factors, computed over the whole horizon that ghost layers
/// complete, so that they correct the quadrature and not a missing part).
enum class VolumeCorrection { none, linear, exact, moment, gradient, fitted, tensor };

template <>
struct EnumName<SurfaceCorrection> {
  static constexpr NameTable<SurfaceCorrection, 6> table{{
      {"none", SurfaceCorrection::none, "no correction"},
      {"volume", SurfaceCorrection::volume, "volume method"},
      {"energy", SurfaceCorrection::energy, "energy method"},
      {"macek-silling", SurfaceCorrection::macek_silling,
       "classical over PD energy density under isotropic expansion"},
      {"tensor", SurfaceCorrection::tensor, "tensor method"},
      {"ghost", SurfaceCorrection::ghost,
       "ghost layers outside free surfaces, quadratic-exact (ghost_layers.hpp)"},
  }};
};

template <>
struct EnumName<VolumeCorrection> {
  static constexpr NameTable<VolumeCorrection, 7> table{{
      {"none", VolumeCorrection::none, "full neighbour volumes"},
      {"linear", VolumeCorrection::linear, "partial volume of cut cells, linear in the distance"},
      {"exact", VolumeCorrection::exact, "partial volume of cut cells, exact"},
      {"moment", VolumeCorrection::moment, "moment-matched lattice weights"},
      {"gradient", VolumeCorrection::gradient,
       "lattice weights matching the 4th moments and the strain-gradient energy of a cell"},
      {"fitted", VolumeCorrection::fitted,
       "per-pair weights giving every particle's own neighbourhood the continuum's moments"},
      {"tensor", VolumeCorrection::tensor,
       "per-particle factors giving its own neighbourhood the continuum's uniaxial-stress "
       "energies (the mesh bodies' default)"},
  }};
};

/// What the corrections read of a model: its dimension, lattice, horizon rule and the two
/// corrections (ModelSpec::corrections()). The horizon rule and the corrections have no defaults
/// here: ModelSpec holds the library's, and whoever builds a CorrectionSpec names all three.
struct CorrectionSpec {
  ModelDimension dimension;
  LatticeSpec lattice;
  HorizonRule horizon_rule;
  SurfaceCorrection surface_correction;
  VolumeCorrection volume_correction;
  /// The particles are not a lattice (a mesh body's elements): `gradient` weights are then solved
  /// per particle (particle_gradient_weights) instead of per lattice orbit.
  bool unstructured = false;

  /// Whether any correction applies, i.e. whether bonds carry factors other than 1.
  bool corrects() const {
    return surface_correction != SurfaceCorrection::none ||
           volume_correction != VolumeCorrection::none;
  }
};

/// Fraction of neighbour j's volume that counts for a bond of reference length r, for the
/// corrections that depend on r alone (`none`, `linear`). `exact` depends on the bond vector:
/// see exact_volume_fraction.
double volume_fraction(VolumeCorrection correction, double r, double horizon, double spacing);

/// Exact fraction of an axis-aligned cell of edge `edge` centred at `centre` (relative to the
/// particle) that lies inside the ball |x| ≤ radius, in dimension `dim` (1: segment, 2: square,
/// 3: cube; unused coordinates ignored). Accurate to ~1e-11 (see corrections.cpp).
double cell_fraction_in_ball(int dim, const Vec3& centre, double edge, double radius);

/// `exact` partial-volume factor of a bond ξ: the fraction of the neighbour's cell (edge λ,
/// centred on the neighbour) inside the horizon sphere of the particle.
double exact_volume_fraction(int dim, const Vec3& xi, double horizon, double spacing);

/// Family volume Σ_j V_j·(volume fraction) of a particle in the bulk of the spec's lattice:
/// the V0 of the `volume` surface correction (the lattice sum, not 4πδ³/3, so that quadrature
/// error does not become a spurious bulk factor).
double bulk_family_volume(const CorrectionSpec& spec);

/// Continuum moments of a full horizon that the bond-based constants are calibrated to:
///  uniaxial: ∫_H n_x⁴ |ξ| dV  (πδ⁴/5 in 3D, t·πδ³/4 in 2D, A·δ² in 1D)
///  isotropic: ∫_H |ξ| dV      (πδ⁴ in 3D, t·2πδ³/3 in 2D, A·δ² in 1D)
/// With c from material.hpp, ¼·c·ε²·(uniaxial moment) is the classical energy density ½Mε² of a
/// uniaxial strain ε and ¼·c·ε²·(isotropic moment) that of an isotropic expansion, (9/2)Kε² in 3D.
double uniaxial_energy_moment(const ModelDimension& d, double horizon);
double isotropic_energy_moment(const ModelDimension& d, double horizon);

/// Partial-volume factor of every directed bond (CSR order) for spec.volume_correction.
std::vector<double> volume_correction_factors(const CorrectionSpec& spec,
                                              const ParticleSet& particles,
                                              const BondFamily& family);

/// Energy method (Madenci & Oterkus): per particle and axis d < dim, the ratio of the classical
/// to the PD strain-energy density under a uniaxial strain along d, both with the bond weights
/// `volume_factor` (the partial-volume factors of the same bonds). Unused axes hold 1.
std::vector<std::array<double, 3>> energy_surface_factors(const CorrectionSpec& spec,
                                                          const ParticleSet& particles,
                                                          const BondFamily& family,
                                                          const std::vector<double>& volume_factor);

/// Continuum moment of a full horizon under uniaxial stress along one axis:
///   ∫_H ((1+ν)n_x² − ν)² |ξ| dV = (1+ν)²·(uniaxial moment) − 2ν(1+ν)/dim·(isotropic moment)
///                                 + ν²·(isotropic moment),
/// with ν = 1/(dim+1), the in-plane Poisson ratio of an isotropic central-force model (1/4 in 3D,
/// 1/3 in 2D for plane stress and plane strain alike; in 1D every bond has n_x² = 1 and ν drops
/// out). ¼·c·ε²·(this moment) is ½Eε² in 3D and 1D, ½E'ε² in 2D (E' = E plane stress,
/// E/(1 − ν²) plane strain): πδ⁴/6 in 3D, t·2πδ³/9 in 2D, A·δ² in 1D.
double uniaxial_stress_energy_moment(const ModelDimension& d, double horizon);

/// `tensor` correction: per particle a diagonal tensor G_i = diag(g_x, g_y, g_z) (unused axes 1)
/// such that particle i's own halves of its bonds, each scaled by n·G_i·n, store the classical
/// energy density of a uniaxial stress along every axis (see corrections.cpp). Bond weights
/// `volume_factor` as in energy_surface_factors.
std::vector<std::array<double, 3>> tensor_surface_factors(const CorrectionSpec& spec,
                                                          const ParticleSet& particles,
                                                          const BondFamily& family,
                                                          const std::vector<double>& volume_factor);

/// Per-particle factor of the `macek-silling` correction (see corrections.cpp for what it is and
/// how sure we are of the source): classical over PD energy density under isotropic expansion.
std::vector<double> isotropic_surface_factors(const CorrectionSpec& spec,
                                              const ParticleSet& particles,
                                              const BondFamily& family,
                                              const std::vector<double>& volume_factor);

/// Names as written in scene files.
const char* to_string(SurfaceCorrection s);
const char* to_string(VolumeCorrection v);
inline constexpr auto all_surface_corrections = enum_values<SurfaceCorrection>();
inline constexpr auto all_volume_corrections = enum_values<VolumeCorrection>();

/// All names in enum order (index = enum value), for tables over every combination.
std::array<const char*, all_surface_corrections.size()> surface_correction_names();
std::array<const char*, all_volume_corrections.size()> volume_correction_names();

/// Moment-matched bond weights w = α + β Σ_a n_a⁴ (`volume_correction: moment`): the lattice
/// sums Σ w V |ξ| n_x⁴ and Σ w V |ξ| n_x²n_y² over a bulk family equal the continuum integrals, so
/// the bulk elastic constants are exact for homogeneous strain (the patch test's interior ratio
/// is 1 by construction, and the lattice's spurious Poisson ratio — 0.2775 at δ = 3.015λ without
/// weights — becomes the bond-based 1/4).
struct MomentWeights {
  double alpha = 1;
  double beta = 0;
  static double cubic_invariant(const Vec3& xi) {
    const double r2 = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    return (xi[0] * xi[0] * xi[0] * xi[0] + xi[1] * xi[1] * xi[1] * xi[1] +
            xi[2] * xi[2] * xi[2] * xi[2]) /
           (r2 * r2);
  }
  double weight(const Vec3& xi) const { return alpha + beta * cubic_invariant(xi); }
};
MomentWeights moment_matched_weights(const CorrectionSpec& spec);

/// Gradient-matched bond weights (`volume_correction: gradient`): one non-negative weight per
/// orbit of lattice offsets under the cube's symmetry group, such that over a bulk family
///  * the weighted 4th moments are the continuum's (as `moment`), and
///  * for a quadratic displacement field the particle's energy density beyond its centre value,
///    (c/16) Σ w V |ξ|³ (Σ n_a n_b n_c ∂_c ε_ab)², equals what its own cell holds when the strain
///    varies linearly across it, (λ²/24) Σ_c ∂_c ε : C : ∂_c ε, for bending and twist fields
///    (gradient_weights.cpp lists them);
/// and, among such weights, the closest to uniform (least Σ_orbits N_o (w_o − w̄)²).
/// The weights concentrate the stiffness on the shortest bonds (3D, m = 3.015, 2√3, 4: only the
/// orbits with |o|² ≤ 4 carry weight).
/// Throws std::runtime_error when no non-negative solution exists, which is always the case in
/// 1D and 2D: there the shortest bonds that feel the gradient already hold 3 times the cell's
/// gradient energy per unit of the matched moment (gradient_weights.cpp).
struct GradientWeights {
  struct Orbit {
    std::array<long long, 3> offset; ///< representative: sorted |components|, e.g. (0, 0, 1)
    std::size_t count = 0;           ///< N_o, offsets of the bulk family in the orbit
    double weight = 0;               ///< w_o
  };
  std::vector<Orbit> orbits; ///< by |o|², then by representative
  double uniform = 1;        ///< w̄: the uniform weight that matches the uniaxial 4th moment
  double residual = 0;       ///< largest relative residual of the equations that were solved
  /// What the weights match: everything; the fourth moments only (horizons below about 2λ have
  /// too few orbits for the gradient fields); or neither exactly (below √2 λ in 2D and 3D), the
  /// least-residual non-negative weights of the fourth moments.
  enum class Matched {
    moments_and_gradient,
    moments,
    closest
  } matched = Matched::moments_and_gradient;
  /// Weight of a bond ξ: that of the orbit of round(ξ/λ). A bond that rounds to an offset outside
  /// the table (jittered particles near the horizon) takes the count-weighted mean weight of the
  /// shell of orbits whose |o| is nearest to |ξ|/λ (the outermost shell: weight 0 in 3D so far).
  double weight(const Vec3& xi, double spacing) const;
  /// Length of the longest offset with a non-zero weight, in spacings.
  double reach() const;
};
GradientWeights gradient_matched_weights(const CorrectionSpec& spec);
/// `volume_correction: gradient` on an unstructured set (a mesh body's particles): the equations of
/// the lattice's `gradient` weights, solved per particle over its own bonds (ghosts included)
/// instead of per lattice orbit, with the zero 3rd moment a lattice has by symmetry and the
/// gradient fields along every axis (gradient_weights.cpp). A pair takes the mean of its two
/// ends' weights.
struct ParticleGradientWeights {
  std::vector<double> factor;   ///< per directed bond (CSR order), the same for both directions
  std::size_t matched = 0;      ///< body particles whose moments and gradient fields were met
  std::size_t moments_only = 0; ///< ... whose 4th and 3rd moments only were met
  std::size_t unmatched = 0;    ///< ... whose moments could not be met: their weights stay 1
  double residual = 0;          ///< largest relative residual of the equations that were met
  double seconds = 0;           ///< wall time of the solve

  /// The body particles the solve ran on: none where it did not run.
  std::size_t particles() const { return matched + moments_only + unmatched; }
};
ParticleGradientWeights particle_gradient_weights(const CorrectionSpec& spec,
                                                  const ParticleSet& particles,
                                                  const BondFamily& family, std::size_t body_count);

/// Fitted bond weights (`volume_correction: fitted`), for particle sets that are not a lattice
/// (jittered, varying volumes): one weight w_p ≥ 0 per pair, used at both ends so that momentum
/// is balanced, such that every particle i whose neighbourhood fills its horizon (the volume
/// centroid of its bonds within 0.1 δ of it) has
///  * the continuum's 4th moments, Σ_j w V_j |ξ| n⊗n⊗n⊗n = (U/3)(δδ + δδ + δδ) (U the uniaxial
///    moment), so its stress and energy density under any uniform strain are the continuum's, and
///  * no 3rd moment, Σ_j w V_j n⊗n⊗n = 0, so a uniform strain leaves it no force;
/// and among such weights those closest to 1 (least Σ_p (w_p − 1)², fitted_weights.cpp).
struct FittedWeights {
  std::vector<double> factor;   ///< per directed bond (CSR order), the same for both directions
  std::size_t matched = 0;      ///< particles whose moments were fitted
  double residual = 0;          ///< largest residual of their equations, relative to U
  std::size_t zero_weights = 0; ///< pairs whose weight non-negativity held at 0
  double smallest_positive = 0; ///< smallest non-zero weight
  double largest = 0;           ///< largest weight
};
FittedWeights fitted_bond_weights(const CorrectionSpec& spec, const ParticleSet& particles,
                                  const BondFamily& family);

/// The longest bond that keeps a stiffness, in spacings: the outermost orbit with a non-zero
/// weight under `gradient` weights (2 at δ = 2√3 λ; one spacing more on an unstructured set,
/// whose particles solve their own), the horizon factor otherwise. Ghost sites
/// beyond it would carry only bonds of zero weight, so none are made (model.cpp, resources.cpp).
double stiff_bond_reach(const CorrectionSpec& spec);
/// The same with the `gradient` weights already solved.
double stiff_bond_reach(const CorrectionSpec& spec, const GradientWeights& weights);

/// Where ghost sites are looked for: the lattice with its horizon shortened to stiff_bond_reach,
/// and the rule that goes with it (inclusive where shortened: the reach is an offset's length).
struct GhostSiteReach {
  LatticeSpec lattice;
  HorizonRule rule = HorizonRule::inclusive;
};
GhostSiteReach ghost_site_reach(const CorrectionSpec& spec);
/// The same with the weights already solved (they cost seconds at large horizons).
GhostSiteReach ghost_site_reach(const CorrectionSpec& spec, const GradientWeights& weights);

/// How much more energy the weighted bonds crossing a plane store than unweighted ones at the
/// same stretch: Σ_{ξ_n > 0} w ξ_n |ξ| / Σ_{ξ_n > 0} ξ_n |ξ| over the bulk-lattice offsets, n the
/// last active axis and w the bulk weight of spec.volume_correction (1 for `none`). The critical
/// stretch derived from a fracture energy assumes uniform weights; dividing it by √ratio keeps the
/// energy to break all bonds crossing a plane (model.cpp).
double fracture_energy_weight_ratio(const CorrectionSpec& spec);

/// The product of the surface and volume correction factors for every directed bond, in CSR
/// order. All ones when both corrections are `none`.
/// Particles from `body_count` on are ghosts (ghost_layers.hpp): per-particle factors are the body
/// particles' own, and a bond between a body particle and a ghost takes the body particle's.
/// `solved`, where given, receives what the per-particle `gradient` solve of an unstructured set
/// met (its counts, residual and time; `factor` left empty); untouched otherwise.
std::vector<double> bond_correction_factors(const CorrectionSpec& spec,
                                            const ParticleSet& particles, const BondFamily& family,
                                            std::size_t body_count = static_cast<std::size_t>(-1),
                                            ParticleGradientWeights* solved = nullptr);

} // namespace pd
