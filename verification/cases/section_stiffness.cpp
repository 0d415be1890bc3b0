#include "section_stiffness.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace pd::verification {

namespace {

enum class Mode { bending, shear, membrane };

struct Prism {
  Model model;
  std::vector<std::size_t> slice; ///< particles of the middle slice (or column)
  std::map<std::pair<long long, long long>, std::size_t> slice_index; ///< by section cell
  double centre_depth = 0;
};

/// Lattice cell of a position across the section (depth, and width for a beam).
std::pair<long long, long long> cell_of(const Vec3& p, int depth, int width, bool plate,
                                        double spacing) {
  const auto index = [&](double x) { return std::llround(2.0 * x / spacing); };
  return {index(p[depth]), plate ? 0LL : index(p[width])};
}

Prism build_prism(const ModelSpec& spec, const BodySpec& body, int span, int depth, int width,
                  bool plate) {
  const double spacing = spec.lattice.spacing;
  // Long enough that every particle within δ of the middle slice has a full horizon along the
  // long axes, so its correction factors are those of an infinite prism.
  const auto cells = static_cast<long long>(std::ceil(2.0 * spec.lattice.horizon() / spacing));
  const double length = static_cast<double>(2 * cells + 1) * spacing;

  ModelSpec prism = spec;
  prism.supports.clear();
  prism.loads.clear();
  BodySpec solid = body;
  Box box = body.region.boxes.front();
  box.hi[span] = box.lo[span] + length;
  if (plate) {
    box.hi[width] = box.lo[width] + length;
  }
  solid.region.boxes = {box};
  prism.bodies = {solid};

  Prism out{build_model(prism), {}, {}, 0.5 * (box.lo[depth] + box.hi[depth])};
  const auto& pos = out.model.particles.position;
  const auto nearest = [&](int axis) {
    const double mid = 0.5 * (box.lo[axis] + box.hi[axis]);
    double best = pos.front()[axis];
    for (const Vec3& p : pos) {
      if (std::abs(p[axis] - mid) < std::abs(best - mid)) {
        best = p[axis];
      }
    }
    return best;
  };
  const double s0 = nearest(span);
  const double w0 = plate ? nearest(width) : 0.0;
  for (std::size_t i = 0; i < pos.size(); ++i) {
    if (std::abs(pos[i][span] - s0) > 0.25 * spacing ||
        (plate && std::abs(pos[i][width] - w0) > 0.25 * spacing)) {
      continue;
    }
    out.slice_index.emplace(cell_of(pos[i], depth, width, plate, spacing), out.slice.size());
    out.slice.push_back(i);
  }
  return out;
}

/// Relaxed PD energy of the slice per unit length (beam) or area (plate) for a unit amplitude.
double relaxed_energy(const Prism& prism, Mode mode, int span, int depth, int width, bool plate) {
  const Model& m = prism.model;
  const double spacing = m.spec.lattice.spacing;
  const auto& pos = m.particles.position;
  // Unknowns: the depth (and, for a beam, width) displacement of each slice particle.
  const std::size_t per = plate ? 1 : 2;
  const auto unknowns = static_cast<Eigen::Index>(per * prism.slice.size());
  std::vector<std::pair<std::size_t, std::size_t>> bonds; // (slice index, directed bond)
  for (std::size_t a = 0; a < prism.slice.size(); ++a) {
    const std::size_t i = prism.slice[a];
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      bonds.emplace_back(a, k);
    }
  }
  Eigen::MatrixXd matrix = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(bonds.size()), unknowns);
  Eigen::VectorXd target(static_cast<Eigen::Index>(bonds.size()));
  for (std::size_t row = 0; row < bonds.size(); ++row) {
    const auto [a, k] = bonds[row];
    const std::size_t i = prism.slice[a];
    const std::size_t j = m.family.neighbour[k];
    const auto found = prism.slice_index.find(cell_of(pos[j], depth, width, plate, spacing));
    if (found == prism.slice_index.end()) {
      throw std::runtime_error("section_stiffness: a neighbour has no counterpart in the slice");
    }
    const std::size_t b = found->second;
    const Vec3 xi{pos[j][0] - pos[i][0], pos[j][1] - pos[i][1], pos[j][2] - pos[i][2]};
    const double length = 1.0 / m.family.inverse_length[k];
    // Energy density ¼·c_ij V_j·|ξ|·s² with s = ξ·Δu/|ξ|², times the particle volume.
    const double weight =
        std::sqrt(0.25 * bond_stiffness(m, k) * length * m.particles.volume[i]) / (length * length);
    const auto r = static_cast<Eigen::Index>(row);
    double imposed = 0; // ξ·Δu of the imposed field
    switch (mode) {
    case Mode::bending: // the curvature at the bond's midpoint
      imposed = xi[span] * xi[span] * (0.5 * (pos[i][depth] + pos[j][depth]) - prism.centre_depth);
      break;
    case Mode::shear:
      imposed = xi[span] * xi[depth];
      break;
    case Mode::membrane:
      imposed = xi[span] * xi[span];
      break;
    }
    target(r) = -weight * imposed;
    const auto col = [&](std::size_t particle, std::size_t component) {
      return static_cast<Eigen::Index>(per * particle + component);
    };
    matrix(r, col(b, 0)) += weight * xi[depth];
    matrix(r, col(a, 0)) -= weight * xi[depth];
    if (!plate) {
      matrix(r, col(b, 1)) += weight * xi[width];
      matrix(r, col(a, 1)) -= weight * xi[width];
    }
  }
  // Rigid translations of the section are in the null space; the minimum-norm solution is fine.
  const Eigen::VectorXd relaxed = matrix.completeOrthogonalDecomposition().solve(target);
  const double energy = (matrix * relaxed - target).squaredNorm();
  return energy / (plate ? spacing * spacing : spacing);
}

} // namespace

int axis_of(const std::string& name) {
  if (name == "x") {
    return 0;
  }
  if (name == "y") {
    return 1;
  }
  if (name == "z") {
    return 2;
  }
  throw std::runtime_error("axis must be x, y or z, got '" + name + "'");
}

SectionStiffness section_stiffness(const ModelSpec& spec, const BodySpec& body, int span, int depth,
                                   bool plate) {
  if (spec.dimension.dim != 3) {
    throw std::runtime_error("section_stiffness: needs a 3D model");
  }
  if (span == depth || span < 0 || depth < 0 || span > 2 || depth > 2) {
    throw std::runtime_error("section_stiffness: span and depth must be two different axes");
  }
  const int width = 3 - span - depth;
  const Prism prism = build_prism(spec, body, span, depth, width, plate);

  const Material& mat = spec.materials.at(static_cast<std::size_t>(body.material));
  const double e = mat.youngs_modulus * mat.stiffness_factor;
  const double nu = mat.poisson_ratio;
  const double g = e / (2.0 * (1.0 + nu));
  const Box& box = body.region.boxes.front();
  const double h = box.hi[depth] - box.lo[depth];
  const double b = plate ? 1.0 : box.hi[width] - box.lo[width];
  const double axial = plate ? e / (1.0 - nu * nu) : e; // ε_width = 0 in a plate

  SectionStiffness out;
  out.section_particles = prism.slice.size();
  out.bending = relaxed_energy(prism, Mode::bending, span, depth, width, plate) /
                (0.5 * axial * b * h * h * h / 12.0);
  out.shear = relaxed_energy(prism, Mode::shear, span, depth, width, plate) / (0.5 * g * b * h);
  out.membrane =
      relaxed_energy(prism, Mode::membrane, span, depth, width, plate) / (0.5 * axial * b * h);
  return out;
}

} // namespace pd::verification
