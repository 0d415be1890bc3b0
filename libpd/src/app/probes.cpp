// Probes of a run: binding probe specs to particles and writing their history.
#include "libpd/app/probes.hpp"

#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

namespace pd {

std::vector<ResolvedProbe> resolve_probes(const std::vector<ProbeSpec>& probes,
                                          const Model& model) {
  std::vector<ResolvedProbe> out;
  const int dim = model.spec.dimension.dim;
  const double tol = 1e-6 * model.spec.lattice.spacing;
  for (const ProbeSpec& p : probes) {
    ResolvedProbe r{p.name, p.component, {}};
    if (p.kind == ProbeSpec::Kind::point) {
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
    if (r.particles.empty()) {
      throw std::runtime_error("probe '" + p.name + "' selects no particle");
    }
    out.push_back(std::move(r));
  }
  return out;
}

double probe_value(const ResolvedProbe& probe, const Simulation& sim) {
  double sum = 0;
  for (std::uint32_t i : probe.particles) {
    sum += sim.displacement(i, probe.component);
  }
  return sum / static_cast<double>(probe.particles.size());
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

std::string probes_csv(const std::vector<ResolvedProbe>& probes, const ProbeHistory& history) {
  std::string s = "time";
  for (const auto& p : probes) {
    s += "," + p.name;
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
