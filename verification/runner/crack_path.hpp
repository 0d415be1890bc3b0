// Reading a crack out of a damage field, for the dynamic fracture cases (kalthoff-winkler,
// glass-branching): which particles lie on a crack, the direction of a crack path, the tip of a
// running crack, where a path splits, and the speed no mode-I crack may exceed (Rayleigh's).
#pragma once

#include "libpd/core/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

namespace pd::verification {

/// A particle lies on a crack when it has lost at least this fraction of its bonds. On the
/// default lattice (m = 2√3, 2D) a particle on either face of a straight crack between two rows
/// loses a third of its bonds and the next row a twelfth, so the threshold keeps the faces and
/// drops the rows beside them whatever the crack's direction.
inline constexpr double crack_damage_threshold = 0.3;

/// Direction of the principal axis of the points (total least squares), in degrees in
/// [0, 180) from +x. Throws std::invalid_argument for fewer than two distinct points.
inline double principal_axis_degrees(const std::vector<Vec3>& p) {
  if (p.size() < 2) {
    throw std::invalid_argument("principal_axis_degrees: needs two or more points");
  }
  const double n = static_cast<double>(p.size());
  double mx = 0, my = 0;
  for (const Vec3& q : p) {
    mx += q[0] / n;
    my += q[1] / n;
  }
  double sxx = 0, syy = 0, sxy = 0;
  for (const Vec3& q : p) {
    sxx += (q[0] - mx) * (q[0] - mx);
    syy += (q[1] - my) * (q[1] - my);
    sxy += (q[0] - mx) * (q[1] - my);
  }
  if (!(sxx + syy > 0)) {
    throw std::invalid_argument("principal_axis_degrees: the points coincide");
  }
  const double deg = 0.5 * std::atan2(2 * sxy, sxx - syy) * 180 / std::numbers::pi;
  return deg < 0 ? deg + 180 : deg;
}

/// The x where a crack running along +x splits: the first column of particles (columns of
/// width `spacing`, from x_from on) whose crack points form two or more groups along y separated
/// by a gap wider than `gap`, and that stays split over the next `persist` of x (a lone damaged
/// particle beside the path is not a branch). nullopt if the path never splits.
inline std::optional<double> branching_x(const std::vector<Vec3>& crack_points, double x_from,
                                         double spacing, double gap, double persist) {
  std::map<long, std::vector<double>> columns; // column index → y of its crack points
  for (const Vec3& q : crack_points) {
    if (q[0] >= x_from) {
      columns[std::lround(std::floor((q[0] - x_from) / spacing))].push_back(q[1]);
    }
  }
  auto split = [&](long c) {
    auto it = columns.find(c);
    if (it == columns.end()) {
      return false;
    }
    std::vector<double> y = it->second;
    std::sort(y.begin(), y.end());
    for (std::size_t k = 1; k < y.size(); ++k) {
      if (y[k] - y[k - 1] > gap) {
        return true;
      }
    }
    return false;
  };
  const long reach = std::lround(std::ceil(persist / spacing));
  for (const auto& [c, ys] : columns) {
    bool stays = true;
    for (long k = 0; k <= reach && stays; ++k) {
      stays = split(c + k);
    }
    if (stays) {
      return x_from + (static_cast<double>(c) + 0.5) * spacing;
    }
  }
  return std::nullopt;
}

/// Rayleigh wave speed of an isotropic solid with shear wave speed c_s and longitudinal speed
/// c_p: the root ξ = c_R/c_s in (0, 1) of (2 − ξ²)² = 4 √(1 − ξ²) √(1 − ξ² c_s²/c_p²), by
/// bisection: left side minus right is negative just above the trivial root 0 and 1 at ξ = 1.
inline double rayleigh_wave_speed(double shear_speed, double longitudinal_speed) {
  const double k2 = (shear_speed * shear_speed) / (longitudinal_speed * longitudinal_speed);
  auto f = [&](double xi) {
    const double x2 = xi * xi;
    return (2 - x2) * (2 - x2) - 4 * std::sqrt(1 - x2) * std::sqrt(1 - x2 * k2);
  };
  double lo = 1e-3, hi = 1.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi) * shear_speed;
}

/// In-plane wave speeds of a 2D elastic sheet: plane stress c_p² = E/(ρ(1 − ν²)), plane strain
/// c_p² = E(1 − ν)/(ρ(1 + ν)(1 − 2ν)); both c_s² = E/(2ρ(1 + ν)).
struct WaveSpeeds {
  double longitudinal = 0;
  double shear = 0;
  double rayleigh = 0;
};
inline WaveSpeeds plane_wave_speeds(double youngs_modulus, double poisson_ratio, double density,
                                    bool plane_stress) {
  const double nu = poisson_ratio;
  WaveSpeeds w;
  w.shear = std::sqrt(youngs_modulus / (2 * density * (1 + nu)));
  w.longitudinal = plane_stress
                       ? std::sqrt(youngs_modulus / (density * (1 - nu * nu)))
                       : std::sqrt(youngs_modulus * (1 - nu) / (density * (1 + nu) * (1 - 2 * nu)));
  w.rayleigh = rayleigh_wave_speed(w.shear, w.longitudinal);
  return w;
}

/// Crack-tip speed from tip positions sampled in time: over every pair of samples `window`
/// apart (the first sample at or after t + window), the chord |r(t + window) − r(t)| over the
/// time between them. A tip found on the lattice moves in jumps of one spacing; the window
/// spreads that jump over several samples. Returns the largest such speed (0 with fewer than
/// two samples a window apart).
inline double max_chord_speed(const std::vector<double>& t, const std::vector<Vec3>& r,
                              double window) {
  double fastest = 0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < t.size() && t[j] - t[i] < window) {
      ++j;
    }
    if (j >= t.size()) {
      break;
    }
    const double d = std::hypot(r[j][0] - r[i][0], r[j][1] - r[i][1]);
    fastest = std::max(fastest, d / (t[j] - t[i]));
  }
  return fastest;
}

} // namespace pd::verification
