// Probes of a run: binding probe specs to particles and writing their history.
#include "libpd/app/probes.hpp"

#include "libpd/core/text.hpp"
#include "libpd/discretisation/mirror_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <stdexcept>

namespace pd {

namespace {

/// The particles a support holds, with the components each is held in (bit c: held by a fixed
/// or prescribed value in c); a reaction keeps those held in its component, a moment all.
void support_particles(const ProbeSpec& p, const Model& model, ResolvedProbe& r) {
  const auto spec = std::find_if(model.spec.supports.begin(), model.spec.supports.end(),
                                 [&](const SupportSpec& s) { return s.name == p.support; });
  if (spec == model.spec.supports.end()) {
    throw std::runtime_error("probe '" + p.name + "' reads unknown support '" + p.support + "'");
  }
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  const bool all = p.quantity == ProbeSpec::Quantity::moment;
  std::map<std::uint32_t, std::uint8_t> held;
  for (const Constraint& c : model.constraints) {
    if ((all || c.component == p.component) && c.mirror_of == Constraint::no_mirror &&
        c.particle < model.body_particle_count() &&
        spec->region.contains(model.particles.position[c.particle], dim, tol)) {
      held[c.particle] = static_cast<std::uint8_t>(held[c.particle] | (1U << c.component));
    }
  }
  for (const auto& [i, mask] : held) {
    r.particles.push_back(i);
    r.role.push_back(mask);
  }
}

using Tensor = std::array<std::array<double, 3>, 3>;

/// Stress of particle i from its bond forces, the virial ½ Σ_j f_ij ⊗ ξ_ij V_j (Lehoucq &
/// Silling 2008 for a homogeneous deformation) with the linearised bond force c V_j s ξ/|ξ|: exact
/// for the bond-based micro-elastic law at small strain. A bond into a ghost or clamp dependant
/// counts ½ in the model's energy (ghost_layers.hpp) but whole in the particle's own stress, so
/// its weight is undone; broken bonds carry nothing, plastic stretch is taken off.
Tensor bond_stress(const Model& m, const std::vector<std::uint8_t>& dependant, const double* y,
                   std::size_t i) {
  const Vec3& xi0 = m.particles.position[i];
  Tensor sigma{};
  for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
    if (!m.state.broken.empty() && m.state.broken[k] != 0) {
      continue;
    }
    const std::size_t j = m.family.neighbour[k];
    const double inv = m.family.inverse_length[k];
    double length2 = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      const double d = y[3 * j + a] - y[3 * i + a];
      length2 += d * d;
    }
    double s = std::sqrt(length2) * inv - 1.0;
    if (!m.state.plastic_stretch.empty()) {
      s -= m.state.plastic_stretch[k];
    }
    const double weight = dependant[j] != 0 && dependant[i] == 0 ? 2.0 : 1.0;
    const double f = 0.5 * weight * bond_stiffness(m, k) * s * inv;
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t b = 0; b < 3; ++b) {
        sigma[a][b] +=
            f * (m.particles.position[j][a] - xi0[a]) * (m.particles.position[j][b] - xi0[b]);
      }
    }
  }
  // Why: a 2D model's bonds lie in the plane, so the virial has no σ_zz; in plane strain the
  // body holds ε_zz = 0 with σ_zz = ν (σ_xx + σ_yy), ν the one the bond model represents.
  if (m.spec.dimension.dim == 2 && m.spec.dimension.plane == PlaneMode::plane_strain) {
    sigma[2][2] =
        bond_based_poisson_ratio(m.spec.dimension).value_or(0.) * (sigma[0][0] + sigma[1][1]);
  }
  return sigma;
}

/// Small strain of particle i: the displacement gradient fitted over its unbroken bonds by least
/// squares, ∇u = (Σ (u_j − u_i) ⊗ ξ V_j)(Σ ξ ⊗ ξ V_j)⁻¹ (the non-local deformation gradient of
/// correspondence models), exact for a linear displacement field whatever the family's shape,
/// so also at a surface. In 2D the out-of-plane components are not read.
Tensor fitted_strain(const Model& m, const double* y, std::size_t i) {
  const int dim = m.spec.dimension.dim;
  Tensor shape{};
  Tensor moment{};
  const Vec3& xi0 = m.particles.position[i];
  for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
    if (!m.state.broken.empty() && m.state.broken[k] != 0) {
      continue;
    }
    const std::size_t j = m.family.neighbour[k];
    const Vec3& xj = m.particles.position[j];
    const double v = m.particles.volume[j];
    for (int a = 0; a < dim; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      const double du = (y[3 * j + ua] - xj[ua]) - (y[3 * i + ua] - xi0[ua]);
      for (int b = 0; b < dim; ++b) {
        const auto ub = static_cast<std::size_t>(b);
        const double xi_b = xj[ub] - xi0[ub];
        shape[ua][ub] += (xj[ua] - xi0[ua]) * xi_b * v;
        moment[ua][ub] += du * xi_b * v;
      }
    }
  }
  Tensor inverse{};
  if (dim == 2) {
    const double det = shape[0][0] * shape[1][1] - shape[0][1] * shape[1][0];
    inverse[0][0] = shape[1][1] / det;
    inverse[1][1] = shape[0][0] / det;
    inverse[0][1] = -shape[0][1] / det;
    inverse[1][0] = -shape[1][0] / det;
  } else {
    const auto& k = shape;
    const double det = k[0][0] * (k[1][1] * k[2][2] - k[1][2] * k[2][1]) -
                       k[0][1] * (k[1][0] * k[2][2] - k[1][2] * k[2][0]) +
                       k[0][2] * (k[1][0] * k[2][1] - k[1][1] * k[2][0]);
    for (std::size_t a = 0; a < 3; ++a) {
      for (std::size_t b = 0; b < 3; ++b) {
        // Cofactor of k[b][a] over det: the adjugate's (a, b) entry.
        const std::size_t r0 = (b + 1) % 3;
        const std::size_t r1 = (b + 2) % 3;
        const std::size_t c0 = (a + 1) % 3;
        const std::size_t c1 = (a + 2) % 3;
        inverse[a][b] = (k[r0][c0] * k[r1][c1] - k[r0][c1] * k[r1][c0]) / det;
      }
    }
  }
  Tensor eps{};
  Tensor grad{};
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t b = 0; b < 3; ++b) {
      for (std::size_t c = 0; c < 3; ++c) {
        grad[a][b] += moment[a][c] * inverse[c][b];
      }
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t b = 0; b < 3; ++b) {
      eps[a][b] = 0.5 * (grad[a][b] + grad[b][a]);
    }
  }
  return eps;
}

double tensor_component(const Tensor& t, int component) {
  const auto& ab = tensor_component_axes[static_cast<std::size_t>(component)];
  return t[static_cast<std::size_t>(ab[0])][static_cast<std::size_t>(ab[1])];
}

} // namespace

double von_mises(const Tensor& s) {
  const double d01 = s[0][0] - s[1][1];
  const double d12 = s[1][1] - s[2][2];
  const double d20 = s[2][2] - s[0][0];
  const double shear = s[0][1] * s[0][1] + s[1][2] * s[1][2] + s[2][0] * s[2][0];
  return std::sqrt(0.5 * (d01 * d01 + d12 * d12 + d20 * d20) + 3.0 * shear);
}

namespace {

/// The body particle nearest x; ties go to the lowest index so the choice is reproducible. A cut
/// cell whose site lies outside its body (lattice.hpp) is passed over: a value read there has no
/// counterpart in the continuum the FE reference solves.
std::uint32_t nearest_particle(const Model& model, const Vec3& x) {
  double best = std::numeric_limits<double>::max();
  std::uint32_t arg = 0;
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
    const BodySpec& body = model.spec.bodies[model.particles.body[i]];
    if (!body.points && !body.region.contains(model.particles.position[i], dim, tol)) {
      continue;
    }
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = model.particles.position[i][c] - x[c];
      d2 += d * d;
    }
    if (d2 < best * (1 - 1e-12)) {
      best = d2;
      arg = static_cast<std::uint32_t>(i);
    }
  }
  return arg;
}

} // namespace

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes,
                                          const Model& model) {
  std::vector<ResolvedProbe> out;
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (const ProbeSpec& p : probes) {
    ResolvedProbe r;
    r.name = p.name;
    r.component = p.component;
    r.quantity = p.quantity;
    r.about = p.about;
    if (p.kind == ProbeSpec::Kind::support) {
      support_particles(p, model, r);
    } else if (p.kind == ProbeSpec::Kind::point) {
      r.particles.push_back(nearest_particle(model, p.point));
      if (p.quantity == ProbeSpec::Quantity::opening) {
        r.particles.push_back(nearest_particle(model, p.to));
        if (r.particles[0] == r.particles[1]) {
          throw std::runtime_error("opening probe '" + p.name +
                                   "': 'point' and 'to' are nearest to the same particle");
        }
        r.role = {0, 1};
        double length = 0;
        for (std::size_t c = 0; c < 3; ++c) {
          r.direction[c] = p.to[c] - p.point[c];
          length += r.direction[c] * r.direction[c];
        }
        for (std::size_t c = 0; c < 3; ++c) {
          r.direction[c] /= std::sqrt(length);
        }
      }
    } else {
      for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
        if (p.region.contains(model.particles.position[i], dim, tol)) {
          r.particles.push_back(static_cast<std::uint32_t>(i));
        }
      }
    }
    if (p.quantity == ProbeSpec::Quantity::stress || p.quantity == ProbeSpec::Quantity::von_mises) {
      r.dependant = energy_dependants(model.size(), model.spec.mirror_coupling, model.constraints,
                                      model.extrapolated);
    }
    if (r.particles.empty()) {
      throw std::runtime_error("probe '" + p.name + "' selects no particle");
    }
    r.count = r.particles.size();
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<ResolvedProbe> localise_probes(std::vector<ResolvedProbe> probes, const Model& local) {
  const Ownership& own = local.ownership;
  std::vector<std::int64_t> local_of(own.global_particles, -1);
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (own.owns(i)) {
      local_of[own.global(i)] = static_cast<std::int64_t>(i);
    }
  }
  for (ResolvedProbe& p : probes) {
    std::vector<std::uint32_t> mine;
    std::vector<std::uint8_t> roles;
    for (std::size_t k = 0; k < p.particles.size(); ++k) {
      const std::uint32_t g = p.particles[k];
      if (local_of[g] >= 0) {
        mine.push_back(static_cast<std::uint32_t>(local_of[g]));
        if (!p.role.empty()) {
          roles.push_back(p.role[k]);
        }
      }
    }
    p.particles = std::move(mine);
    p.role = std::move(roles);
    if (!p.dependant.empty()) {
      p.dependant = energy_dependants(local.size(), local.spec.mirror_coupling, local.constraints,
                                      local.extrapolated);
    }
  }
  return probes;
}

double probe_value(const ResolvedProbe& probe, const Simulation& sim) {
  const Model& model = sim.model();
  // Exact, and over the particles this rank owns: the same value on any number of ranks.
  ExactSum sum;
  const double* y = sim.state().position.data();
  for (std::size_t k = 0; k < probe.particles.size(); ++k) {
    const std::uint32_t i = probe.particles[k];
    switch (probe.quantity) {
    case ProbeSpec::Quantity::displacement:
      sum.add(sim.displacement(i, probe.component));
      break;
    case ProbeSpec::Quantity::reaction:
      // The particle is held: the support balances the body's force on it (a load on a held
      // particle goes straight into the support and is not part of the reaction).
      sum.add(-sim.state().force[3 * i + static_cast<std::size_t>(probe.component)] *
              model.particles.volume[i]);
      break;
    case ProbeSpec::Quantity::moment: {
      // (x − about) × R about the axis, R the reaction in the components the particle is held
      // in, x its reference position (small displacements).
      const auto a = static_cast<std::size_t>(probe.component);
      const std::size_t b = (a + 1) % 3;
      const std::size_t c = (a + 2) % 3;
      const auto reaction = [&](std::size_t d) {
        return (static_cast<unsigned>(probe.role[k]) & (1U << d)) != 0
                   ? -sim.state().force[3 * i + d] * model.particles.volume[i]
                   : 0.0;
      };
      const Vec3& x = model.particles.position[i];
      sum.add((x[b] - probe.about[b]) * reaction(c));
      sum.add(-(x[c] - probe.about[c]) * reaction(b));
      break;
    }
    case ProbeSpec::Quantity::stress:
      sum.add(tensor_component(bond_stress(model, probe.dependant, y, i), probe.component));
      break;
    case ProbeSpec::Quantity::strain:
      sum.add(tensor_component(fitted_strain(model, y, i), probe.component));
      break;
    case ProbeSpec::Quantity::von_mises:
      sum.add(von_mises(bond_stress(model, probe.dependant, y, i)));
      break;
    case ProbeSpec::Quantity::opening:
      for (std::size_t c = 0; c < 3; ++c) {
        const double u = sim.displacement(i, static_cast<int>(c)) * probe.direction[c];
        sum.add(probe.role[k] == 0 ? -u : u);
      }
      break;
    case ProbeSpec::Quantity::damage:
      sum.add(model.state.damage.empty() ? 0.0 : model.state.damage[i]);
      break;
    }
  }
  const double total = model.ownership.communicator().sum(sum);
  return probe_sums(probe.quantity) ? total : total / static_cast<double>(probe.count);
}

void ProbeHistory::record(const std::vector<ResolvedProbe>& probes, const Simulation& sim) {
  time.push_back(sim.state().time);
  std::vector<double> row;
  for (const auto& p : probes) {
    row.push_back(probe_value(p, sim));
  }
  values.push_back(std::move(row));
}

ProbeHistory ProbeHistory::finite_rows() const {
  ProbeHistory clean;
  for (std::size_t r = 0; r < time.size(); ++r) {
    bool finite = true;
    for (double v : values[r]) {
      finite = finite && std::isfinite(v);
    }
    if (finite) {
      clean.time.push_back(time[r]);
      clean.values.push_back(values[r]);
    }
  }
  return clean;
}

namespace {

/// A probe name as one CSV header cell: valid UTF-8 (any reader takes the file), and quoted
/// (RFC 4180) when it holds a separator, a quote or a line break.
std::string csv_cell(const std::string& name) {
  std::string text = valid_utf8(name);
  if (text.find_first_of(",\"\r\n") == std::string::npos) {
    return text;
  }
  std::string quoted(1, '"');
  for (const char c : text) {
    quoted.push_back(c);
    if (c == '"') {
      quoted.push_back('"');
    }
  }
  quoted.push_back('"');
  return quoted;
}

} // namespace

std::string probes_csv(const std::vector<ResolvedProbe>& probes, const ProbeHistory& history) {
  std::string s = "time";
  for (const auto& p : probes) {
    s += ',';
    s += csv_cell(p.name);
  }
  s += "\n";
  for (std::size_t r = 0; r < history.time.size(); ++r) {
    s += fmt::format("{}", history.time[r]);
    for (double v : history.values[r]) {
      s += fmt::format(",{}", v);
    }
    s += "\n";
  }
  return s;
}

} // namespace pd
