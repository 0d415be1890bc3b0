// A discretised PD model ready to run: particles, bond families, bond parameters and history,
// supports and loads. Built once from a ModelSpec (normally read from a scene file).
#pragma once

#include "libpd/core/names.hpp"
#include "libpd/discretisation/bond_family.hpp"
#include "libpd/discretisation/corrections.hpp"
#include "libpd/discretisation/fibre_arms.hpp"
#include "libpd/discretisation/ghost_layers.hpp"
#include "libpd/discretisation/lattice.hpp"
#include "libpd/discretisation/mirror_constraints.hpp"
#include "libpd/discretisation/ownership.hpp"
#include "libpd/physics/effects.hpp"
#include "libpd/physics/material.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace pd {

inline constexpr double no_limit = std::numeric_limits<double>::infinity();

/// Bond stiffness and strengths. Either one value for the whole body (uniform) or one value per
/// directed bond (per-bond field): the kernel is compiled for one of the two.
struct BondField {
  double stiffness = 0;                      ///< c·V_j [N/m³ per unit stretch], uniform case
  double critical_stretch = no_limit;        ///< s0, uniform case
  double yield_stretch = no_limit;           ///< s_Y, uniform case
  std::vector<double> bond_stiffness;        ///< c_ij·V_j·(correction factors), per bond
  std::vector<double> bond_critical_stretch; ///< allocated only with damage
  std::vector<double> bond_yield_stretch;    ///< allocated only with plasticity

  bool per_bond() const { return !bond_stiffness.empty(); }
};

/// History that only some effects need; each array is allocated only when its effect is on.
struct BondState {
  std::vector<std::uint8_t> broken;    ///< per directed bond, damage only
  std::vector<double> plastic_stretch; ///< per directed bond, plasticity only
  std::vector<double> damage;          ///< per particle damage index φ (eq. 13), damage only
  /// Set by the quasi-static driver (time/quasi_static.hpp) for the fibre model: each arm's
  /// plastic stretch at the start of the current increment, from which the kernel recomputes it
  /// at every evaluation. Empty otherwise (the plastic stretch then accumulates in place).
  std::vector<double> plastic_stretch_at_increment_start;
};

struct BoxRegionLoad {
  Region region;
  enum class Kind { total, per_area, per_length, body, point, pressure } kind = Kind::total;
  Vec3 value{0, 0, 0};
  double measure = 1;  ///< area [m²] or length [m] for per_area / per_length
  Vec3 point{0, 0, 0}; ///< kind point: where the force acts (load_particles says on which)
  /// kind pressure: the shape on whose surface it acts, where that surface bounds a body
  /// (surface_load.hpp), and the pressure [Pa], positive pushing into the body
  Shape surface;
  double pressure = 0;
};

template <>
struct EnumName<BoxRegionLoad::Kind> {
  using Kind = BoxRegionLoad::Kind;
  static constexpr NameTable<Kind, 6> table{{
      {"total", Kind::total, "total force [N] spread over the region"},
      {"per_area", Kind::per_area, "traction [N/m²] on the loaded area"},
      {"per_length", Kind::per_length, "line load [N/m] on the loaded length"},
      {"body", Kind::body, "body force density [N/m³]"},
      {"point", Kind::point, "force [N] at a point, shared by the particles nearest it"},
      {"pressure", Kind::pressure, "pressure [Pa] on the surface of a shape, into the body"},
  }};
};

struct SupportSpec {
  std::string name;
  Region region;
  std::array<bool, 3> fixed{false, false, false};
  std::array<bool, 3> prescribed{false, false, false};
  Vec3 displacement{0, 0, 0};
  /// Set by code, not by a scene file: the prescribed displacement at each particle's reference
  /// position, taking the place of the uniform `displacement` in the prescribed components. A
  /// verification case uses it to hold a boundary zone at a closed-form field (the elliptical
  /// disk's eq. 116 of Olsson et al.); the load ramp scales it like `displacement`.
  std::function<Vec3(const Vec3&)> displacement_field;
  /// Clamped face without a rigid block: each particle of the support takes the displacement of
  /// its mirror image across the planes x_a = mirror_at[a] (every a with mirror[a]), negated once
  /// per plane. The displacement then vanishes on the face with the strain continuous across it,
  /// where a block of fixed particles leaves the bonds into it elastic over their whole length
  /// and so puts the clamp about one spacing behind the face.
  std::array<bool, 3> mirror{false, false, false};
  Vec3 mirror_at{0, 0, 0};
  /// Symmetry planes x_a = symmetry_at[a] (every a with symmetry[a]): the body lies on one side
  /// and the model is half (a quarter, …) of a symmetric one. The lattice sites beyond the plane
  /// within reach of the body's bonds take the displacement of their image with the normal
  /// component negated: normal displacement zero on the plane, tangential free. A roller on a
  /// whole face is the same condition. `region` may be empty: the whole plane.
  std::array<bool, 3> symmetry{false, false, false};
  Vec3 symmetry_at{0, 0, 0};
  bool mirrors() const { return mirror[0] || mirror[1] || mirror[2]; }
  bool symmetric() const { return symmetry[0] || symmetry[1] || symmetry[2]; }
};

struct LoadSpec {
  std::string name;
  BoxRegionLoad load;
};

/// Everything needed to build the discrete model (no solver settings).
struct ModelSpec {
  ModelDimension dimension;
  LatticeSpec lattice;
  HorizonRule horizon_rule = HorizonRule::inclusive;
  std::vector<Material> materials;
  std::vector<BodySpec> bodies;
  std::vector<SupportSpec> supports;
  std::vector<LoadSpec> loads;
  std::vector<Crack> cracks; ///< pre-cracks: no bond crosses them
  EffectSet effects;
  FibreKernel fibre_kernel; ///< read only under effects.bond_model = virtual_fibres
  /// The library's defaults, which a scene file that names none of the keys under `model` also
  /// takes (io/scene/model_options.cpp reads them from here): the treatment that is right in
  /// tension and in bending for any box or union of boxes. Ghost layers outside free surfaces and
  /// clamps extrapolated by the quadratics that vanish on their faces give every body particle
  /// the bulk energy of any quadratic field (ghost_layers.hpp); the `gradient` bond weights make
  /// that bulk energy the continuum's, cell by cell, for uniform strain and for bending
  /// (corrections.hpp). The bare model is `none` + `none` (+ `copy`), said explicitly.
  SurfaceCorrection surface_correction = SurfaceCorrection::ghost;
  VolumeCorrection volume_correction = VolumeCorrection::gradient;
  MirrorCoupling mirror_coupling = MirrorCoupling::quadratic;

  /// Whether a body is a mesh's elements (BodySpec::mesh, filled with its elements): an
  /// unstructured set.
  bool has_mesh_body() const {
    for (const BodySpec& b : bodies) {
      if (b.mesh && b.fill == MeshFill::elements) {
        return true;
      }
    }
    return false;
  }

  /// What the bond corrections read of the model (corrections.hpp). The fibre model reads
  /// `gradient` as the moment weights (fibre_arms.hpp), so its ghost layers reach the whole
  /// horizon, not only the bonds that `gradient` weights keep stiff.
  CorrectionSpec corrections() const {
    const bool fibres = effects.bond_model == BondModel::virtual_fibres &&
                        volume_correction == VolumeCorrection::gradient;
    return {dimension,
            lattice,
            horizon_rule,
            surface_correction,
            fibres ? VolumeCorrection::moment : volume_correction,
            effects.bond_model != BondModel::virtual_fibres && has_mesh_body()};
  }
};

/// The corrections of a bond-based model with a mesh body: the lattice's defaults. Ghost layers,
/// as on the lattice: the lattice sites outside the part (outside its elements, ghost_layers.hpp)
/// continue every body particle's horizon, quadratic-exact. `gradient` weights cannot be looked up
/// by lattice offset on an unstructured set, so each particle's are solved over its own bonds
/// (particle_gradient_weights, corrections.hpp), then `tensor`'s axis factors restore the
/// uniaxial energies that sharing a pair's weight between its two ends moves; so a thin part
/// bends as the continuum does (docs/scenes.md, meshes).
inline constexpr SurfaceCorrection mesh_surface_correction = SurfaceCorrection::ghost;
inline constexpr VolumeCorrection mesh_volume_correction = VolumeCorrection::gradient;

/// Whether a volume correction needs the lattice (a mesh body cannot take it): what it says why,
/// or nullptr. Every surface correction works on any set.
inline const char* lattice_only(VolumeCorrection v) {
  switch (v) {
  case VolumeCorrection::moment:
    return "its weights are per lattice offset, looked up by rounding a bond to the lattice";
  case VolumeCorrection::exact:
    return "it cuts the neighbour's cubic lattice cell by the horizon";
  default:
    return nullptr;
  }
}

/// For `pd info` and the run summary: a bond-based model with a mesh body names the corrections it
/// runs with and why they are not the lattice defaults; "" for any other model.
std::string mesh_corrections_note(const ModelSpec& spec);

struct Model {
  ModelSpec spec;
  ParticleSet particles;
  BondFamily family;
  BondField field;
  BondState state;
  EffectSet effects;
  FibreArms fibre_arms;                ///< the arm weights, virtual fibres only (fibre_arms.hpp)
  std::vector<double> density;         ///< per particle [kg/m³]
  std::vector<Constraint> constraints; ///< sorted by particle, then component
  /// Ghost particles and quadratically extrapolated clamp particles (ghost_layers.hpp): massless,
  /// set from their sources after every update, their forces folded back onto the sources.
  ExtrapolatedParticles extrapolated;
  /// The last `ghost_count` particles are ghost sites outside the bodies (surface_correction
  /// `ghost`); supports, loads, probes and output see only the body particles before them.
  std::size_t ghost_count = 0;
  std::vector<double> external_force_density; ///< 3N, full (unramped) load [N/m³]
  /// Per crack of spec.cracks: the bonds (pairs) it kept from being created.
  std::vector<std::size_t> bonds_cut_by_crack;
  /// What the per-particle `gradient` weights of an unstructured set met (mesh bodies;
  /// corrections.hpp), its `factor` empty; no particles() where no such solve ran.
  ParticleGradientWeights particle_weights;
  /// The particles this process owns when the run is split over MPI ranks (ownership.hpp);
  /// a serial model owns all of them.
  Ownership ownership;

  std::size_t size() const { return particles.size(); }
  std::size_t body_particle_count() const { return particles.size() - ghost_count; }
  double horizon() const { return spec.lattice.horizon(); }
  /// Bytes held by the model (particles, families, bond field and history).
  std::size_t memory_bytes() const;
};

/// The effect axes the force kernel is compiled for: the effects `spec` declares, plus the two
/// that follow from the model rather than being declared, a per-bond field (several materials
/// in use, a surface or volume correction, varying particle volumes, or consistently coupled
/// mirror supports, whose bonds are weighted) and body forces (a load
/// of kind `body`). `materials_used`: how many distinct materials the particles carry.
EffectSet kernel_effects(const ModelSpec& spec, std::size_t materials_used);

/// Bytes a model holds per particle, per directed bond and per constraint: the one account of a
/// model's memory, behind both Model::memory_bytes() (actual counts) and estimate_resources
/// (counts estimated from the specification), so the two cannot drift apart.
struct ModelStorage {
  std::size_t per_particle = 0; ///< particle set, CSR offset, density, loads, damage, run state
  std::size_t per_directed_bond = 0; ///< CSR neighbour and 1/|ξ|, per-bond field, bond history
  static constexpr std::size_t per_constraint = sizeof(Constraint);
  /// An extrapolated particle (index and CSR offset) and each of its terms (source, coefficient).
  static constexpr std::size_t per_dependant = sizeof(std::uint32_t) + sizeof(std::size_t);
  static constexpr std::size_t per_extrapolation_term = sizeof(std::uint32_t) + sizeof(double);
  /// Bytes that do not grow with the model: the closing entry of the CSR offsets. The resource
  /// estimate leaves them out.
  static constexpr std::size_t fixed = sizeof(std::size_t);

  /// Bytes of the storage that grows with the model, for counts of type T (std::size_t for the
  /// actual model, double for estimates).
  template <class T>
  T bytes(T particles, T directed_bonds, T constraints) const {
    return particles * static_cast<T>(per_particle) +
           directed_bonds * static_cast<T>(per_directed_bond) +
           constraints * static_cast<T>(per_constraint);
  }
};

/// The storage of a model of `spec` whose kernel runs with `effects` (kernel_effects).
ModelStorage model_storage(const ModelSpec& spec, const EffectSet& effects);

/// A support that cannot act as specified; `support` is its index in ModelSpec::supports.
struct SupportError : std::runtime_error {
  SupportError(std::size_t index, const std::string& what)
      : std::runtime_error(what), support(index) {}
  std::size_t support;
};

/// The constraints of spec.supports on the first `body_particles` of `particles` (all of them by
/// default), sorted by particle and component (a later support overrides an earlier one on the
/// same component). Mirror supports under `quadratic` coupling add none: their particles are
/// extrapolated (clamp_planes). Throws SupportError for a support that holds no particle or whose
/// mirror images are not free lattice particles.
std::vector<Constraint> support_constraints(const ModelSpec& spec, const ParticleSet& particles,
                                            std::size_t body_particles = SIZE_MAX);

/// The clamp planes of spec's mirror supports, each with the side its support's region lies on.
std::vector<ClampPlane> clamp_planes(const ModelSpec& spec);

/// The body particles (of the first `body_count`) a load acts on: those in its region, for a
/// point load the particles nearest its point (all within 10⁻⁶ λ of the nearest distance), for a
/// pressure the particles next to its surface (pressure_forces, surface_load.hpp).
std::vector<std::uint32_t> load_particles(const ModelSpec& spec, const ParticleSet& particles,
                                          const LoadSpec& load, std::size_t body_count);

/// Build particles, families, bond parameters, supports and loads.
/// Throws std::runtime_error for inconsistent specs that the scene checker did not catch.
Model build_model(const ModelSpec& spec);

/// The lattice's toughness ratio (src/discretisation/lattice_toughness.cpp): the K at which a
/// straight crack along a lattice axis runs in `spec`'s lattice with its corrections, over
/// √(E' G0) (E' = E in plane stress, E/(1 − ν²) in plane strain), for the energy-derived s0
/// (critical_stretch_from_fracture_energy); s0 from G0 is divided by it. Computed in plane
/// stress in 2D, for a plane-strained straight front in 3D, and cached per (dimension, m, horizon
/// rule, corrections); nullopt in 1D (no crack tip).
std::optional<double> lattice_toughness_ratio(const ModelSpec& spec);

/// The computation behind it in `spec`'s own plane mode (2D) or in plane strain (3D), not cached.
double lattice_toughness_ratio_in(const ModelSpec& spec);
/// The same on particles already generated from spec's dimension, lattice and bodies.
Model build_model(const ModelSpec& spec, ParticleSet particles);

/// The model's extrapolated particles (Model::extrapolated) fitted again, each from its sources
/// within `fit_radius` λ of its nearest one (refit_within, ghost_layers.hpp): fewer sources per
/// dependant, an operator the static solver factors as its preconditioner.
ExtrapolatedParticles refit_extrapolation(const Model& m, double fit_radius);

/// Bond stiffness of directed bond k, c_ij·V_j·corrections, whichever storage the model uses.
inline double bond_stiffness(const Model& m, std::size_t k) {
  return m.field.per_bond() ? m.field.bond_stiffness[k] : m.field.stiffness;
}

} // namespace pd
