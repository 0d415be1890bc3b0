// Probes of a run: binding probe specs to particles and writing their history.
#include "libpd/app/probes.hpp"

#include "libpd/core/text.hpp"
#include "libpd/discretisation/mirror_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

namespace pd {

namespace {

/// The particles a support holds in the probe's component (by a fixed or prescribed value).
std::vector<std::uint32_t> support_particles(const ProbeSpec& p, const Model& model) {
  const auto spec = std::find_if(model.spec.supports.begin(), model.spec.supports.end(),
                                 [&](const SupportSpec& s) { return s.name == p.support; });
  if (spec == model.spec.supports.end()) {
    throw std::runtime_error("probe '" + p.name + "' reads unknown support '" + p.support + "'");
  }
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  std::vector<std::uint32_t> out;
  for (const Constraint& c : model.constraints) {
    if (c.component == p.component && c.mirror_of == Constraint::no_mirror &&
        c.particle < model.body_particle_count() &&
        spec->region.contains(model.particles.position[c.particle], dim, tol)) {
      out.push_back(c.particle);
    }
  }
  return out;
}

/// Normal stress σ_cc of particle i from its bond forces, the virial ½ Σ_j f_ij ⊗ ξ_ij V_j
/// (Lehoucq & Silling 2008 for a homogeneous deformation) with the linearised bond force
/// c V_j s ξ/|ξ|: exact for the bond-based micro-elastic law at small strain. A bond into a ghost
/// or clamp dependant counts ½ in the model's energy (ghost_layers.hpp) but whole in the particle's
/// own stress, so its weight is undone; broken bonds carry nothing, plastic stretch is taken off.
double normal_stress(const Model& m, const std::vector<std::uint8_t>& dependant, const double* y,
                     std::size_t i, int component) {
  const auto c = static_cast<std::size_t>(component);
  const Vec3& xi0 = m.particles.position[i];
  double sigma = 0;
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
    const double xi_c = m.particles.position[j][c] - xi0[c];
    const double weight = dependant[j] != 0 && dependant[i] == 0 ? 2.0 : 1.0;
    sigma += 0.5 * weight * bond_stiffness(m, k) * s * xi_c * xi_c * inv;
  }
  return sigma;
}

} // namespace

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes,
                                          const Model& model) {
  std::vector<ResolvedProbe> out;
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (const ProbeSpec& p : probes) {
    ResolvedProbe r{p.name, p.component, {}, p.quantity, {}};
    if (p.kind == ProbeSpec::Kind::support) {
      r.particles = support_particles(p, model);
    } else if (p.kind == ProbeSpec::Kind::point) {
      // Nearest particle; ties go to the lowest index so the choice is reproducible.
      double best = std::numeric_limits<double>::max();
      std::uint32_t arg = 0;
      for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
        double d2 = 0;
        for (int c = 0; c < 3; ++c) {
          const double d = model.particles.position[i][c] - p.point[c];
          d2 += d * d;
        }
        if (d2 < best * (1 - 1e-12)) {
          best = d2;
          arg = static_cast<std::uint32_t>(i);
        }
      }
      r.particles.push_back(arg);
    } else {
      for (std::size_t i = 0; i < model.body_particle_count(); ++i) {
        if (p.region.contains(model.particles.position[i], dim, tol)) {
          r.particles.push_back(static_cast<std::uint32_t>(i));
        }
      }
    }
    if (p.quantity == ProbeSpec::Quantity::stress) {
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
    for (const std::uint32_t g : p.particles) {
      if (local_of[g] >= 0) {
        mine.push_back(static_cast<std::uint32_t>(local_of[g]));
      }
    }
    p.particles = std::move(mine);
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
  for (std::uint32_t i : probe.particles) {
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
    case ProbeSpec::Quantity::stress:
      sum.add(
          normal_stress(model, probe.dependant, sim.state().position.data(), i, probe.component));
      break;
    case ProbeSpec::Quantity::damage:
      sum.add(model.state.damage.empty() ? 0.0 : model.state.damage[i]);
      break;
    }
  }
  const double total = model.ownership.communicator().sum(sum);
  return probe.quantity == ProbeSpec::Quantity::reaction ? total
                                                         : total / static_cast<double>(probe.count);
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
