#include "libpd/discretisation/bond_family.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pd {

namespace {

/// Particles binned into cubic cells of edge δ: a particle's neighbours are in its own cell or in
/// one of the 3^dim − 1 adjacent cells.
struct CellList {
  Vec3 lo{0, 0, 0};
  double cell = 1;
  std::array<long long, 3> count{1, 1, 1};
  std::vector<std::size_t> start;    // size cells + 1
  std::vector<std::uint32_t> member; // particle indices grouped by cell

  long long cell_index(const std::array<long long, 3>& c) const {
    return (c[2] * count[1] + c[1]) * count[0] + c[0];
  }
  std::array<long long, 3> coords(const Vec3& p) const {
    std::array<long long, 3> c{};
    for (int a = 0; a < 3; ++a) {
      c[a] = std::clamp(static_cast<long long>((p[a] - lo[a]) / cell), 0LL, count[a] - 1);
    }
    return c;
  }
};

CellList make_cell_list(const std::vector<Vec3>& x, int dim, double horizon) {
  CellList cl;
  cl.cell = horizon;
  Vec3 hi{0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    cl.lo[a] = std::numeric_limits<double>::max();
    hi[a] = std::numeric_limits<double>::lowest();
  }
  for (const Vec3& p : x) {
    for (int a = 0; a < 3; ++a) {
      cl.lo[a] = std::min(cl.lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    cl.count[a] = a < dim ? static_cast<long long>((hi[a] - cl.lo[a]) / cl.cell) + 1 : 1;
  }
  const auto cells = static_cast<std::size_t>(cl.count[0] * cl.count[1] * cl.count[2]);
  if (cells > 2'000'000'000ULL) {
    throw std::runtime_error("neighbour search: the body is too large for its horizon");
  }
  cl.start.assign(cells + 1, 0);
  std::vector<std::size_t> cell_of(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    cell_of[i] = static_cast<std::size_t>(cl.cell_index(cl.coords(x[i])));
    ++cl.start[cell_of[i] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) {
    cl.start[c + 1] += cl.start[c];
  }
  cl.member.resize(x.size());
  std::vector<std::size_t> fill(cl.start.begin(), cl.start.end() - 1);
  for (std::size_t i = 0; i < x.size(); ++i) {
    cl.member[fill[cell_of[i]]++] = static_cast<std::uint32_t>(i);
  }
  return cl;
}

template <class Visit>
void for_each_candidate(const CellList& cl, int dim, const Vec3& p, Visit&& visit) {
  const auto c = cl.coords(p);
  std::array<long long, 3> lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = a < dim ? std::max(c[a] - 1, 0LL) : 0;
    hi[a] = a < dim ? std::min(c[a] + 1, cl.count[a] - 1) : 0;
  }
  for (long long k = lo[2]; k <= hi[2]; ++k) {
    for (long long j = lo[1]; j <= hi[1]; ++j) {
      for (long long i = lo[0]; i <= hi[0]; ++i) {
        const auto cell = static_cast<std::size_t>(cl.cell_index({i, j, k}));
        for (std::size_t m = cl.start[cell]; m < cl.start[cell + 1]; ++m) {
          visit(cl.member[m]);
        }
      }
    }
  }
}

} // namespace

BondFamily build_bond_family(const std::vector<Vec3>& x, int dim, double horizon,
                             HorizonRule rule) {
  if (!(horizon > 0)) {
    throw std::invalid_argument("neighbour search: horizon must be positive");
  }
  if (x.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::runtime_error("neighbour search: more than 2^32 particles");
  }
  const InHorizon inside(horizon, rule);
  const CellList cl = make_cell_list(x, dim, inside.reach);
  const auto n = static_cast<std::ptrdiff_t>(x.size());

  auto in_horizon = [&](std::size_t i, std::size_t j) {
    const double d0 = x[j][0] - x[i][0], d1 = x[j][1] - x[i][1], d2 = x[j][2] - x[i][2];
    return inside(d0 * d0 + d1 * d1 + d2 * d2);
  };

  BondFamily f;
  f.offsets.assign(x.size() + 1, 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    std::size_t count = 0;
    for_each_candidate(cl, dim, x[i], [&](std::size_t j) {
      if (j != i && in_horizon(i, j)) {
        ++count;
      }
    });
    f.offsets[i + 1] = count;
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    f.offsets[i + 1] += f.offsets[i];
  }
  f.neighbour.resize(f.offsets.back());
  f.inverse_length.resize(f.offsets.back());
#pragma omp parallel for schedule(dynamic, 256)
  for (std::ptrdiff_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    std::size_t k = f.offsets[i];
    for_each_candidate(cl, dim, x[i], [&](std::size_t j) {
      if (j != i && in_horizon(i, j)) {
        f.neighbour[k++] = static_cast<std::uint32_t>(j);
      }
    });
    std::sort(f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[i]),
              f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[i + 1]));
    for (std::size_t b = f.offsets[i]; b < f.offsets[i + 1]; ++b) {
      const std::size_t j = f.neighbour[b];
      const double d0 = x[j][0] - x[i][0], d1 = x[j][1] - x[i][1], d2 = x[j][2] - x[i][2];
      f.inverse_length[b] = 1.0 / std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    }
  }
  return f;
}

std::vector<std::size_t> reverse_bond_index(const BondFamily& f) {
  std::vector<std::size_t> rev(f.directed_bond_count());
  const std::size_t n = f.particle_count();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = f.offsets[i]; k < f.offsets[i + 1]; ++k) {
      const std::size_t j = f.neighbour[k];
      const auto first = f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[j]);
      const auto last = f.neighbour.begin() + static_cast<std::ptrdiff_t>(f.offsets[j + 1]);
      const auto it = std::lower_bound(first, last, static_cast<std::uint32_t>(i));
      rev[k] = static_cast<std::size_t>(it - f.neighbour.begin());
    }
  }
  return rev;
}

} // namespace pd
