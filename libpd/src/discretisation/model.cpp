#include "libpd/discretisation/model.hpp"

#include "cut_cells.hpp"
#include "libpd/discretisation/bond_cuts.hpp"
#include "libpd/discretisation/surface_load.hpp"
#include "symmetry_images.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

namespace pd {

namespace {

/// Tolerance for "a particle lies in a region": far below λ, far above round-off.
std::string point_text(const Vec3& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buffer;
}

/// Mirror constraints of a support (SupportSpec::mirror): each member takes the displacement of
/// the particle at its reflection across every mirror plane, negated once per plane. The image is
/// looked up on a grid of λ/4, so it must be a lattice point (regular lattices only).
/// A constraint with the index of the support that set it (for error messages).
struct OwnedConstraint {
  Constraint constraint;
  std::size_t support = 0;
};

void add_mirror_constraints(const ParticleSet& particles, double spacing, std::size_t support,
                            const SupportSpec& sup, const std::vector<std::uint32_t>& members,
                            std::vector<OwnedConstraint>& constraints) {
  const double cell = 0.25 * spacing;
  const auto key = [cell](const Vec3& p) {
    return std::array<long long, 3>{std::llround(p[0] / cell), std::llround(p[1] / cell),
                                    std::llround(p[2] / cell)};
  };
  std::map<std::array<long long, 3>, std::uint32_t> at;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    at.emplace(key(particles.position[i]), static_cast<std::uint32_t>(i));
  }
  for (std::uint32_t i : members) {
    Vec3 image = particles.position[i];
    double sign = 1.0;
    for (int a = 0; a < 3; ++a) {
      if (sup.mirror[a]) {
        image[a] = 2.0 * sup.mirror_at[a] - image[a];
        sign = -sign;
      }
    }
    const auto found = at.find(key(image));
    if (found == at.end() || found->second == i) {
      throw SupportError(support, "support '" + sup.name + "': no particle at the mirror image " +
                                      point_text(image) + " of the particle at " +
                                      point_text(particles.position[i]));
    }
    for (std::uint8_t c = 0; c < 3; ++c) {
      constraints.push_back({{i, c, 0.0, found->second, sign}, support});
    }
  }
}

double region_tolerance(const ModelSpec& spec) {
  return 1e-6 * spec.lattice.spacing;
}

struct MaterialConstants {
  double c = 0;
  double critical_stretch = no_limit;
  double yield_stretch = no_limit;
};

std::vector<MaterialConstants> material_constants(const ModelSpec& spec) {
  std::vector<MaterialConstants> out;
  const double delta = spec.lattice.horizon();
  // s0 from G0 (eq. 11 and its 2D forms) makes the energy stored at s0 across a plane G0. In 2D
  // and 3D it is divided by the lattice's toughness ratio (lattice_toughness.cpp), so that a
  // crack runs at K_Ic = √(E' G0) whatever the weights and m. In 1D (no crack tip) `gradient`
  // weights store `ratio` times the energy in the bonds crossing a plane, so s0/√ratio keeps that
  // energy what the uniform lattice releases. Explicit s0 stays.
  double stretch_scale = 1.0;
  for (const Material& m : spec.materials) {
    if (!m.critical_stretch && m.fracture_energy && spec.effects.damage &&
        spec.effects.bond_model == BondModel::micro_elastic) {
      if (const auto toughness = lattice_toughness_ratio(spec)) {
        stretch_scale = 1.0 / *toughness;
      } else if (spec.volume_correction == VolumeCorrection::gradient) {
        stretch_scale = 1.0 / std::sqrt(fracture_energy_weight_ratio(spec.corrections()));
      }
      break;
    }
  }
  for (const Material& m : spec.materials) {
    MaterialConstants k;
    k.c = micromodulus(spec.dimension, m.youngs_modulus, delta) * m.stiffness_factor;
    if (m.critical_stretch) {
      k.critical_stretch = *m.critical_stretch;
    } else if (m.fracture_energy) {
      k.critical_stretch =
          stretch_scale *
          critical_stretch_from_fracture_energy(
              spec.dimension, m.youngs_modulus * m.stiffness_factor, delta, *m.fracture_energy);
    }
    if (m.yield_stretch) {
      k.yield_stretch = *m.yield_stretch;
    }
    out.push_back(k);
  }
  return out;
}

std::vector<std::uint32_t> particles_in(const ParticleSet& ps, const Region& region, int dim,
                                        double tol, std::size_t count = SIZE_MAX) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < std::min(count, ps.size()); ++i) {
    if (region.contains(ps.position[i], dim, tol)) {
      out.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return out;
}

} // namespace

std::vector<Constraint> support_constraints(const ModelSpec& spec, const ParticleSet& particles,
                                            std::size_t body_particles) {
  const double tol = region_tolerance(spec);
  std::vector<OwnedConstraint> constraints;
  // Under quadratic coupling: which body particles the mirror supports extrapolate, and the
  // support holding the most of them, to name if they are all of them.
  std::vector<std::uint8_t> extrapolated(std::min(body_particles, particles.size()), 0);
  std::size_t largest = 0, largest_count = 0;
  for (std::size_t s = 0; s < spec.supports.size(); ++s) {
    const SupportSpec& sup = spec.supports[s];
    if (sup.symmetric()) {
      // A particle on the plane is its own image: its normal displacement is zero. The sites
      // beyond the plane are images (symmetry_images).
      for (std::size_t i = 0; i < std::min(body_particles, particles.size()); ++i) {
        for (std::uint8_t a = 0; a < 3; ++a) {
          if (sup.symmetry[a] && std::abs(particles.position[i][a] - sup.symmetry_at[a]) <= tol &&
              (sup.region.boxes.empty() ||
               sup.region.contains(particles.position[i], spec.dimension.dim, tol))) {
            constraints.push_back({{static_cast<std::uint32_t>(i), a, 0.0}, s});
          }
        }
      }
      continue;
    }
    const auto members =
        particles_in(particles, sup.region, spec.dimension.dim, tol, body_particles);
    if (members.empty()) {
      throw SupportError(s, "support '" + sup.name + "' holds no particle");
    }
    if (sup.mirrors() && spec.mirror_coupling == MirrorCoupling::quadratic) {
      for (std::uint32_t i : members) {
        extrapolated[i] = 1;
      }
      if (members.size() > largest_count) {
        largest = s;
        largest_count = members.size();
      }
      continue; // its particles are extrapolated from the body (extrapolated_particles)
    }
    if (sup.mirrors()) {
      add_mirror_constraints(particles, spec.lattice.spacing, s, sup, members, constraints);
      continue;
    }
    for (std::uint32_t i : members) {
      const Vec3 value =
          sup.displacement_field ? sup.displacement_field(particles.position[i]) : sup.displacement;
      for (std::uint8_t c = 0; c < 3; ++c) {
        if (sup.fixed[c] || sup.prescribed[c]) {
          constraints.push_back({{i, c, sup.prescribed[c] ? value[c] : 0.0}, s});
        }
      }
    }
  }
  if (!extrapolated.empty() && std::all_of(extrapolated.begin(), extrapolated.end(),
                                           [](std::uint8_t e) { return e != 0; })) {
    // Nothing would be left to move or to extrapolate from: every bond would join two
    // extrapolated particles and carry no stiffness.
    throw SupportError(largest, "support '" + spec.supports[largest].name +
                                    "': with the other mirror supports it holds every particle "
                                    "of the bodies, so none is left free to move");
  }
  // Later supports override earlier ones on the same component.
  std::stable_sort(constraints.begin(), constraints.end(),
                   [](const OwnedConstraint& a, const OwnedConstraint& b) {
                     return a.constraint.particle != b.constraint.particle
                                ? a.constraint.particle < b.constraint.particle
                                : a.constraint.component < b.constraint.component;
                   });
  std::vector<OwnedConstraint> merged;
  for (const OwnedConstraint& o : constraints) {
    if (!merged.empty() && merged.back().constraint.particle == o.constraint.particle &&
        merged.back().constraint.component == o.constraint.component) {
      merged.back() = o;
    } else {
      merged.push_back(o);
    }
  }
  // A mirror source must move freely: apply_constraints reads it before the constraints act.
  std::vector<std::uint8_t> held(3 * particles.size(), 0);
  for (const OwnedConstraint& o : merged) {
    held[3 * o.constraint.particle + o.constraint.component] = 1;
  }
  std::vector<Constraint> out;
  out.reserve(merged.size());
  for (const OwnedConstraint& o : merged) {
    const Constraint& c = o.constraint;
    if (c.mirror_of != Constraint::no_mirror && held[3 * c.mirror_of + c.component]) {
      throw SupportError(o.support,
                         "support '" + spec.supports[o.support].name + "': the mirror image " +
                             point_text(particles.position[c.mirror_of]) + " of the particle at " +
                             point_text(particles.position[c.particle]) + " is itself supported");
    }
    out.push_back(c);
  }
  return out;
}

std::vector<ClampPlane> clamp_planes(const ModelSpec& spec) {
  std::vector<ClampPlane> planes;
  for (const SupportSpec& sup : spec.supports) {
    for (int a = 0; a < 3; ++a) {
      const auto au = static_cast<std::size_t>(a);
      if (!sup.mirror[au]) {
        continue;
      }
      double lo = std::numeric_limits<double>::infinity();
      double hi = -lo;
      for (const Box& b : sup.region.boxes) {
        lo = std::min(lo, b.lo[au]);
        hi = std::max(hi, b.hi[au]);
      }
      const double centre = 0.5 * (lo + hi);
      const ClampPlane plane{a, sup.mirror_at[au], centre < sup.mirror_at[au] ? -1.0 : 1.0};
      const bool known = std::any_of(planes.begin(), planes.end(), [&](const ClampPlane& p) {
        return p.axis == plane.axis && p.at == plane.at && p.side == plane.side;
      });
      if (!known) {
        planes.push_back(plane);
      }
    }
  }
  return planes;
}

EffectSet kernel_effects(const ModelSpec& spec, std::size_t materials_used) {
  EffectSet effects = spec.effects;
  // Consistently coupled mirror supports weight their bonds (mirror_constraints.hpp), so they need
  // the per-bond field; so do extrapolated clamps (ghost_layers.hpp).
  const bool weighted_mirrors = spec.mirror_coupling != MirrorCoupling::copy &&
                                std::any_of(spec.supports.begin(), spec.supports.end(),
                                            [](const SupportSpec& s) { return s.mirrors(); });
  // The fibre model's field is the bound of fibre_stiffness_bound, one value per bond.
  effects.per_bond_field = spec.effects.bond_model == BondModel::virtual_fibres ||
                           materials_used > 1 || spec.corrections().corrects() ||
                           spec.has_mesh_body() || spec.lattice.volume_variation > 0 ||
                           weighted_mirrors;
  effects.body_force = std::any_of(spec.loads.begin(), spec.loads.end(), [](const LoadSpec& l) {
    return l.load.kind == BoxRegionLoad::Kind::body;
  });
  return effects;
}

ModelStorage model_storage(const ModelSpec& spec, const EffectSet& effects) {
  // The arrays build_model allocates, each under the condition it allocates them on.
  constexpr std::size_t dbl = sizeof(double);
  ModelStorage s;
  s.per_particle = sizeof(Vec3) + dbl + 2 * sizeof(std::uint16_t); // particle set
  s.per_particle += sizeof(std::size_t);                           // CSR offsets
  s.per_particle += dbl;                                           // density
  s.per_particle += spec.loads.empty() ? 0 : 3 * dbl;              // external force density
  s.per_particle += effects.damage ? dbl : 0;                      // damage index
  s.per_particle += 9 * dbl;                         // run state: positions, velocities, forces
  s.per_directed_bond = sizeof(std::uint32_t) + dbl; // CSR neighbour and 1/|ξ|
  if (effects.per_bond_field) {
    s.per_directed_bond += dbl + (effects.damage ? dbl : 0) + (effects.plasticity ? dbl : 0);
  }
  s.per_directed_bond += (effects.damage ? sizeof(std::uint8_t) : 0) +
                         (effects.plasticity ? dbl : 0); // broken flags, plastic stretch
  if (effects.bond_model == BondModel::virtual_fibres) {
    s.per_directed_bond += 3 * dbl; // the arm weights A, B (fibre_arms.hpp), the kernel's A|ξ|/N
    s.per_particle += 3 * dbl;      // two moduli, and the kernel's mean strain
  }
  return s;
}

std::size_t Model::memory_bytes() const {
  return model_storage(spec, effects)
             .bytes(size(), family.directed_bond_count(), constraints.size()) +
         extrapolated.size() * ModelStorage::per_dependant +
         extrapolated.source.size() * ModelStorage::per_extrapolation_term + ModelStorage::fixed;
}

namespace {

/// Ghost particles at the lattice sites outside the bodies within reach of a bond with stiffness
/// (ghost_layers.hpp, stiff_bond_reach), appended after the body particles. Their material is set
/// once the bond family is known.
void append_ghost_sites(const ModelSpec& spec, ParticleSet& particles) {
  const GhostSiteReach reach = ghost_site_reach(spec.corrections());
  std::vector<const PointCloud*> mesh_of_body;
  for (const BodySpec& b : spec.bodies) {
    mesh_of_body.push_back(b.mesh ? b.points.get() : nullptr);
  }
  const auto sites = ghost_sites(spec.dimension.dim, reach.lattice, reach.rule, particles.position,
                                 mesh_of_body, particles.body);
  const double volume = cell_volume(spec.dimension, spec.lattice.spacing);
  for (const Vec3& p : sites) {
    particles.position.push_back(p);
    particles.volume.push_back(volume);
    particles.material.push_back(particles.material.front());
    particles.body.push_back(particles.body.front());
  }
}

/// A ghost continues the body next to it: it takes the material (and body) of the nearest body
/// particle in its family (lowest index among equals), so a bond into it has that material's
/// constants.
void take_material_of_nearest_body_particle(const BondFamily& family, std::size_t body_count,
                                            ParticleSet& particles) {
  for (std::size_t g = body_count; g < particles.size(); ++g) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = family.offsets[g]; k < family.offsets[g + 1]; ++k) {
      const std::size_t j = family.neighbour[k];
      const double r = 1.0 / family.inverse_length[k];
      if (j < body_count && r < best * (1 - 1e-12)) {
        best = r;
        particles.material[g] = particles.material[j];
        particles.body[g] = particles.body[j];
      }
    }
  }
}

/// Whether a bond between two points is left by the holes (bond_cuts.hpp); null without holes.
std::function<bool(const Vec3&, const Vec3&)> bonded_across_holes(const ModelSpec& spec) {
  if (std::none_of(spec.bodies.begin(), spec.bodies.end(),
                   [](const BodySpec& b) { return !b.region.minus.empty(); })) {
    return nullptr;
  }
  return [&spec](const Vec3& a, const Vec3& b) {
    return !bond_passes_through_hole(spec.dimension.dim, spec.lattice.spacing, spec.bodies, a, b);
  };
}

/// The extrapolated dependants (ghost_layers.hpp): the ghosts, and the particles of mirror
/// supports under `quadratic` coupling. Particles held by any constraint are never sources.
ExtrapolatedParticles extrapolated_particles(const ModelSpec& spec, const ParticleSet& particles,
                                             std::size_t body_count, const BondFamily& family,
                                             const std::vector<Constraint>& constraints) {
  const std::size_t n = particles.size();
  std::vector<std::uint8_t> dependent(n, 0);
  std::vector<std::uint8_t> mirror_image(n, 0); // set by a mirror constraint, not fitted
  for (const Constraint& c : constraints) {
    if (c.mirror_of != Constraint::no_mirror) {
      dependent[c.particle] = 1;
      mirror_image[c.particle] = 1;
    }
  }
  for (std::size_t g = body_count; g < n; ++g) {
    dependent[g] = 1;
  }
  if (spec.mirror_coupling == MirrorCoupling::quadratic) {
    for (const SupportSpec& sup : spec.supports) {
      if (sup.mirrors()) {
        for (std::uint32_t i : particles_in(particles, sup.region, spec.dimension.dim,
                                            region_tolerance(spec), body_count)) {
          dependent[i] = 1;
        }
      }
    }
  }
  std::vector<std::uint32_t> fitted;
  for (std::size_t i = 0; i < n; ++i) {
    if (dependent[i] && !mirror_image[i]) {
      fitted.push_back(static_cast<std::uint32_t>(i));
    }
  }
  if (fitted.empty()) {
    return {};
  }
  const std::vector<SymmetryPlane> symmetry = detail::symmetry_planes(spec, particles, body_count);
  return detail::symmetry_images(
      spec, particles, body_count, region_tolerance(spec), symmetry, constraints,
      extrapolation_ties(spec.dimension.dim, spec.lattice.spacing, particles.position, family,
                         dependent, fitted, clamp_planes(spec), symmetry,
                         bonded_across_holes(spec)));
}

/// The loads as force densities [N/m³] per dof (empty without loads): a resultant is shared in
/// proportion to particle volume among the body particles (ghosts carry none).
std::vector<double> load_force_densities(const ModelSpec& spec, const ParticleSet& particles,
                                         std::size_t body_count) {
  std::vector<double> force_density;
  if (!spec.loads.empty()) {
    force_density.assign(3 * particles.size(), 0.0);
  }
  for (const LoadSpec& load : spec.loads) {
    if (load.load.kind == BoxRegionLoad::Kind::pressure) {
      const SurfaceForces forces =
          pressure_forces(spec.dimension, spec.lattice.spacing, spec.bodies, particles, body_count,
                          load.load.surface, load.load.pressure);
      if (forces.particle.empty()) {
        throw std::runtime_error("pressure load '" + load.name +
                                 "' acts on no particle: its surface bounds no body");
      }
      for (std::size_t k = 0; k < forces.particle.size(); ++k) {
        const std::uint32_t i = forces.particle[k];
        for (std::size_t c = 0; c < 3; ++c) {
          force_density[3 * i + c] += forces.force[k][c] / particles.volume[i];
        }
      }
      continue;
    }
    const auto members = load_particles(spec, particles, load, body_count);
    if (members.empty()) {
      throw std::runtime_error("load '" + load.name + "' acts on no particle");
    }
    double total_volume = 0;
    for (std::uint32_t i : members) {
      total_volume += particles.volume[i];
    }
    for (int c = 0; c < 3; ++c) {
      double density = 0;
      switch (load.load.kind) {
      case BoxRegionLoad::Kind::body:
        density = load.load.value[c];
        break;
      case BoxRegionLoad::Kind::total:
      case BoxRegionLoad::Kind::point:
        density = load.load.value[c] / total_volume;
        break;
      case BoxRegionLoad::Kind::per_area:
      case BoxRegionLoad::Kind::per_length:
        density = load.load.value[c] * load.load.measure / total_volume;
        break;
      case BoxRegionLoad::Kind::pressure:
        break;
      }
      for (std::uint32_t i : members) {
        force_density[3 * i + c] += density;
      }
    }
  }
  return force_density;
}

} // namespace

std::vector<std::uint32_t> load_particles(const ModelSpec& spec, const ParticleSet& particles,
                                          const LoadSpec& load, std::size_t body_count) {
  const int dim = spec.dimension.dim;
  const std::size_t n = std::min(body_count, particles.size());
  if (load.load.kind == BoxRegionLoad::Kind::pressure) {
    return pressure_forces(spec.dimension, spec.lattice.spacing, spec.bodies, particles, n,
                           load.load.surface, load.load.pressure)
        .particle;
  }
  if (load.load.kind != BoxRegionLoad::Kind::point) {
    return particles_in(particles, load.load.region, dim, region_tolerance(spec), n);
  }
  std::vector<double> distance(n);
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0;
    for (std::size_t a = 0; a < static_cast<std::size_t>(dim); ++a) {
      const double d = particles.position[i][a] - load.load.point[a];
      s += d * d;
    }
    distance[i] = std::sqrt(s);
    nearest = std::min(nearest, distance[i]);
  }
  std::vector<std::uint32_t> members;
  for (std::size_t i = 0; i < n; ++i) {
    if (distance[i] <= nearest + 1e-6 * spec.lattice.spacing) {
      members.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return members;
}

namespace {

/// Bonds whose factor is zero (the `gradient` weights beyond two spacings, bonds between two
/// dependants) store no energy and carry no force: they leave the family, so the kernel, the
/// time-step bounds and the damage index never see them. Factors are symmetric in i and j, so
/// every bond keeps its partner.
void drop_bonds_without_stiffness(BondFamily& family, std::vector<double>& factor) {
  if (std::none_of(factor.begin(), factor.end(), [](double f) { return f == 0.0; })) {
    return;
  }
  BondFamily kept;
  kept.offsets.reserve(family.offsets.size());
  kept.offsets.push_back(0);
  std::vector<double> kept_factor;
  for (std::size_t i = 0; i + 1 < family.offsets.size(); ++i) {
    for (std::size_t k = family.offsets[i]; k < family.offsets[i + 1]; ++k) {
      if (factor[k] != 0.0) {
        kept.neighbour.push_back(family.neighbour[k]);
        kept.inverse_length.push_back(family.inverse_length[k]);
        kept_factor.push_back(factor[k]);
      }
    }
    kept.offsets.push_back(kept.neighbour.size());
  }
  family = std::move(kept);
  factor = std::move(kept_factor);
}

/// The virtual-fibre model's arms (fibre_arms.hpp) and, as its per-bond field, the pair
/// stiffness that bounds its operator (for the time step and ADR). Arms between two extrapolated
/// particles carry nothing and leave the family, as for the bond-based model.
void build_fibre_field(Model& m) {
  std::vector<std::uint8_t> owns(m.size(), 1);
  for (const std::uint32_t d : m.extrapolated.particle) {
    owns[d] = 0;
  }
  std::vector<double> keep(m.family.directed_bond_count(), 0.0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      keep[k] = owns[i] || owns[m.family.neighbour[k]] ? 1.0 : 0.0;
    }
  }
  drop_bonds_without_stiffness(m.family, keep);
  m.fibre_arms = fibre_arms(
      m.spec.corrections(), m.spec.fibre_kernel, m.spec.materials, m.particles, m.family,
      fibre_particle_sizes(m.spec.lattice, m.spec.fibre_kernel, m.particles, m.spec.dimension.dim),
      owns);
  m.field.bond_stiffness = fibre_stiffness_bound(m.fibre_arms, m.family);
  // Per arm, the weaker end's limits: the yield strain of eq. 111 and, as a plastic strain, the
  // elongation limit of eq. 118 (δ_e/|ξ|).
  const std::size_t nb = m.family.directed_bond_count();
  const auto& materials = m.spec.materials;
  const auto& material = m.particles.material;
  if (m.effects.plasticity) {
    m.field.bond_yield_stretch.resize(nb);
  }
  if (m.effects.damage) {
    m.field.bond_critical_stretch.resize(nb);
  }
  for (std::size_t i = 0; i < m.size(); ++i) {
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      const Material& a = materials[material[i]];
      const Material& b = materials[material[m.family.neighbour[k]]];
      if (m.effects.plasticity) {
        m.field.bond_yield_stretch[k] =
            std::min(a.yield_stretch.value_or(no_limit), b.yield_stretch.value_or(no_limit));
      }
      if (m.effects.damage) {
        m.field.bond_critical_stretch[k] =
            std::min(a.elongation_limit.value_or(no_limit), b.elongation_limit.value_or(no_limit)) *
            m.family.inverse_length[k];
      }
    }
  }
}

/// Arms of a model with point-cloud bodies (fibre_arms.hpp): each particle's horizon is α·h_a.
BondFamily point_cloud_family(const ModelSpec& spec, const ParticleSet& particles) {
  if (spec.effects.bond_model != BondModel::virtual_fibres) {
    throw std::runtime_error("bodies given as particles need model.bond_model: virtual-fibres");
  }
  const int dim = spec.dimension.dim;
  std::vector<double> horizon =
      fibre_particle_sizes(spec.lattice, spec.fibre_kernel, particles, dim);
  for (double& h : horizon) {
    h *= spec.fibre_kernel.alpha;
  }
  return variable_horizon_family(particles.position, dim, horizon);
}

void require_material_and_body(const ModelSpec& spec) {
  if (spec.materials.empty() || spec.bodies.empty()) {
    throw std::runtime_error("a model needs at least one material and one body");
  }
}

} // namespace

Model build_model(const ModelSpec& spec) {
  require_material_and_body(spec);
  return build_model(spec, generate_lattice(spec.dimension, spec.lattice, spec.bodies));
}

Model build_model(const ModelSpec& spec, ParticleSet particles) {
  require_material_and_body(spec);
  Model m;
  m.spec = spec;
  const int dim = spec.dimension.dim;
  const double delta = spec.lattice.horizon();
  m.particles = std::move(particles);
  // Under the bond-based model a mesh body's particles take the lattice's horizon, like lattice
  // particles; only the virtual-fibre model gives particles horizons of their own.
  if (spec.effects.bond_model != BondModel::virtual_fibres &&
      std::all_of(spec.bodies.begin(), spec.bodies.end(),
                  [](const BodySpec& b) { return !b.points || b.mesh; })) {
    m.particles.particle_size.clear();
    const char* why = spec.has_mesh_body() ? lattice_only(spec.volume_correction) : nullptr;
    if (why != nullptr) {
      throw std::runtime_error(std::string("a mesh body is an unstructured set, but a correction "
                                           "of the model needs a lattice: ") +
                               why);
    }
  }
  const std::size_t body_count = m.particles.size();
  if (body_count == 0) {
    throw std::runtime_error("the bodies contain no lattice particle");
  }
  // Ghost sites are lattice sites: bodies given as particles have none.
  if (spec.surface_correction == SurfaceCorrection::ghost && m.particles.particle_size.empty()) {
    append_ghost_sites(spec, m.particles);
  }
  m.ghost_count = m.particles.size() - body_count;
  const std::size_t n = m.particles.size();
  if (m.particles.particle_size.empty()) {
    m.family = build_bond_family(m.particles.position, dim, delta, spec.horizon_rule);
  } else {
    m.family = point_cloud_family(spec, m.particles);
  }
  m.bonds_cut_by_crack = cut_bonds_across_cracks_and_holes(
      dim, spec.lattice.spacing, spec.cracks, spec.bodies, m.particles, body_count,
      detail::images_of_body_particles(spec, m.particles, body_count), m.family);
  take_material_of_nearest_body_particle(m.family, body_count, m.particles);
  m.constraints = support_constraints(spec, m.particles, body_count);
  m.extrapolated = extrapolated_particles(spec, m.particles, body_count, m.family, m.constraints);

  const std::set<std::uint16_t> used(m.particles.material.begin(), m.particles.material.end());
  m.effects = kernel_effects(spec, used.size());
  const std::vector<double> share = detail::cell_shares(spec, m.particles, body_count);
  m.effects.per_bond_field = m.effects.per_bond_field || !share.empty();

  const auto constants = material_constants(spec);
  m.density.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.density[i] = spec.materials[m.particles.material[i]].density;
  }

  if (m.effects.bond_model == BondModel::virtual_fibres) {
    build_fibre_field(m);
  } else if (!m.effects.per_bond_field) {
    const MaterialConstants& k = constants[*used.begin()];
    m.field.stiffness = k.c * m.particles.volume[0];
    m.field.critical_stretch = k.critical_stretch;
    m.field.yield_stretch = k.yield_stretch;
  } else {
    std::vector<double> correction = bond_correction_factors(
        spec.corrections(), m.particles, m.family, body_count, &m.particle_weights);
    if (consistent_mirror_coupling(spec.mirror_coupling, m.constraints) ||
        !m.extrapolated.empty()) {
      // The energy W_c of mirror_constraints.hpp and ghost_layers.hpp: bonds between a body
      // particle and a dependant count ½, bonds between two dependants 0.
      const auto weight = mirror_bond_weights(
          m.family, energy_dependants(n, spec.mirror_coupling, m.constraints, m.extrapolated));
      for (std::size_t k = 0; k < correction.size(); ++k) {
        correction[k] *= weight[k];
      }
    }
    if (!share.empty() && spec.surface_correction == SurfaceCorrection::ghost) {
      detail::scale_bonds_of_cut_cells(share, detail::energy_weights(spec, m.particles, share),
                                       m.family, m.extrapolated, correction);
    }
    drop_bonds_without_stiffness(m.family, correction);
    const std::size_t nb = m.family.directed_bond_count();
    m.field.bond_stiffness.resize(nb);
    if (m.effects.damage) {
      m.field.bond_critical_stretch.resize(nb);
    }
    if (m.effects.plasticity) {
      m.field.bond_yield_stretch.resize(nb);
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
        const std::size_t j = m.family.neighbour[k];
        // A bond between two materials takes the weaker one's constants (Miranda §5.2: interface
        // bonds have the properties of concrete).
        const MaterialConstants& a = constants[m.particles.material[i]];
        const MaterialConstants& b = constants[m.particles.material[j]];
        m.field.bond_stiffness[k] = std::min(a.c, b.c) * m.particles.volume[j] * correction[k];
        if (m.effects.damage) {
          m.field.bond_critical_stretch[k] = std::min(a.critical_stretch, b.critical_stretch);
        }
        if (m.effects.plasticity) {
          m.field.bond_yield_stretch[k] = std::min(a.yield_stretch, b.yield_stretch);
        }
      }
    }
  }
  if (m.effects.damage) {
    m.state.broken.assign(m.family.directed_bond_count(), 0);
    m.state.damage.assign(n, 0.0);
  }
  if (m.effects.plasticity) {
    m.state.plastic_stretch.assign(m.family.directed_bond_count(), 0.0);
  }

  m.external_force_density = load_force_densities(spec, m.particles, body_count);
  return m;
}

ExtrapolatedParticles refit_extrapolation(const Model& m, double fit_radius) {
  return refit_within(m.spec.dimension.dim, m.spec.lattice.spacing, m.particles.position,
                      m.extrapolated, clamp_planes(m.spec),
                      detail::symmetry_planes(m.spec, m.particles, m.body_particle_count()),
                      fit_radius);
}

} // namespace pd
