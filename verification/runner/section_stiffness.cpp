#include "section_stiffness.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

namespace pd::verification {

namespace {

enum class Mode { bending, shear, membrane };

/// The axes of the section problem: along the span, the bending direction and the third one
/// (across a 3D beam's width, along a plate's width, out of plane in 2D).
struct Axes {
  int span = 0;
  int depth = 2;
  int width = 1;
  bool plate = false;
  /// The section's unknowns per cell: the depth displacement, and the width one for a 3D beam
  /// (its width is free to contract); a plate's width strain and a 2D model's out-of-plane
  /// displacement are zero.
  std::vector<int> components;
};

using Cell = std::pair<long long, long long>;

/// Lattice cell of a position across the section (depth, and width for a 3D beam).
Cell cell_of(const Vec3& p, const Axes& ax, double spacing) {
  const auto index = [&](double x) { return std::llround(2.0 * x / spacing); };
  return {index(p[ax.depth]), ax.components.size() > 1 ? index(p[ax.width]) : 0LL};
}

/// A displacement component as imposed value plus a combination of the section's unknowns.
struct Affine {
  double imposed = 0;
  std::vector<std::pair<Eigen::Index, double>> terms; ///< (unknown, coefficient)
};

struct Prism {
  Model model;
  Axes axes;
  std::vector<std::size_t> slice;        ///< every particle (body or ghost) of the middle slice
  std::map<Cell, std::size_t> cells;     ///< body cells of the section → their index
  std::vector<std::ptrdiff_t> dependant; ///< per particle: its entry in model.extrapolated or −1
  double s0 = 0;                         ///< span coordinate of the slice
  double centre_depth = 0;               ///< the section's neutral axis
};

Prism build_prism(const ModelSpec& spec, const BodySpec& body, const Axes& ax) {
  const double spacing = spec.lattice.spacing;
  // Long enough that every particle within δ of the middle slice has a full horizon along the
  // long axes, and every ghost beside the slice its whole fit cloud (within δ + √6 λ < 2δ), so
  // its bonds, weights and extrapolation are those of an infinite prism.
  const auto cells = static_cast<long long>(std::ceil(2.0 * spec.lattice.horizon() / spacing));
  const double length = static_cast<double>(2 * cells + 1) * spacing;

  ModelSpec prism = spec;
  prism.supports.clear();
  prism.loads.clear();
  BodySpec solid = body;
  Box box = body.region.boxes.front();
  box.hi[ax.span] = box.lo[ax.span] + length;
  if (ax.plate) {
    box.hi[ax.width] = box.lo[ax.width] + length;
  }
  solid.region.boxes = {box};
  prism.bodies = {solid};

  Prism out{build_model(prism), ax, {}, {}, {}, 0, 0.5 * (box.lo[ax.depth] + box.hi[ax.depth])};
  const Model& m = out.model;
  const auto& pos = m.particles.position;
  const auto nearest = [&](int axis) {
    const double mid = 0.5 * (box.lo[axis] + box.hi[axis]);
    double best = pos.front()[axis];
    for (std::size_t i = 0; i < m.body_particle_count(); ++i) {
      if (std::abs(pos[i][axis] - mid) < std::abs(best - mid)) {
        best = pos[i][axis];
      }
    }
    return best;
  };
  out.s0 = nearest(ax.span);
  const double w0 = ax.plate ? nearest(ax.width) : 0.0;
  for (std::size_t i = 0; i < pos.size(); ++i) {
    if (std::abs(pos[i][ax.span] - out.s0) > 0.25 * spacing ||
        (ax.plate && std::abs(pos[i][ax.width] - w0) > 0.25 * spacing)) {
      continue;
    }
    out.slice.push_back(i);
    if (i < m.body_particle_count()) {
      out.cells.emplace(cell_of(pos[i], ax, spacing), out.cells.size());
    }
  }
  out.dependant.assign(pos.size(), -1);
  for (std::size_t d = 0; d < m.extrapolated.size(); ++d) {
    out.dependant[m.extrapolated.particle[d]] = static_cast<std::ptrdiff_t>(d);
  }
  return out;
}

/// The imposed field at x for a unit amplitude, component `axis`.
double imposed(const Prism& p, Mode mode, const Vec3& x, int axis) {
  const Axes& ax = p.axes;
  const double s = x[ax.span] - p.s0;
  const double d = x[ax.depth] - p.centre_depth;
  switch (mode) {
  case Mode::bending: // u_span = κ s d, u_depth = −κ s²/2
    return axis == ax.span ? s * d : axis == ax.depth ? -0.5 * s * s : 0.0;
  case Mode::shear: // u_depth = γ s
    return axis == ax.depth ? s : 0.0;
  case Mode::membrane: // u_span = ε s
    return axis == ax.span ? s : 0.0;
  }
  return 0.0;
}

/// Component `axis` of particle i's displacement: a body particle's is the imposed field plus its
/// cell's unknown; a ghost's is its extrapolation from the body (ghost_layers.hpp), exactly as the
/// model sets it, so the section sees the default surface treatment as a run does.
Affine displacement(const Prism& p, Mode mode, std::size_t i, int axis) {
  const Model& m = p.model;
  const double spacing = m.spec.lattice.spacing;
  const auto unknown = [&](std::size_t particle) -> std::optional<Eigen::Index> {
    const auto& comps = p.axes.components;
    const auto c = std::find(comps.begin(), comps.end(), axis);
    if (c == comps.end()) {
      return std::nullopt;
    }
    const auto cell = p.cells.find(cell_of(m.particles.position[particle], p.axes, spacing));
    if (cell == p.cells.end()) {
      throw std::runtime_error("section_stiffness: a particle has no counterpart in the slice");
    }
    return static_cast<Eigen::Index>(comps.size() * cell->second +
                                     static_cast<std::size_t>(c - comps.begin()));
  };
  Affine a;
  const auto add_body = [&](std::size_t particle, double coefficient) {
    a.imposed += coefficient * imposed(p, mode, m.particles.position[particle], axis);
    if (const auto u = unknown(particle)) {
      a.terms.emplace_back(*u, coefficient);
    }
  };
  if (p.dependant[i] < 0) {
    add_body(i, 1.0);
    return a;
  }
  const ExtrapolatedParticles& e = m.extrapolated;
  const auto d = static_cast<std::size_t>(p.dependant[i]);
  for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
    add_body(e.source[t], e.coefficient[t]);
  }
  return a;
}

/// Relaxed PD energy of the slice per unit length (beam) or area (plate) for a unit amplitude:
/// W_c of every particle of the slice, ghosts included (their bonds into the body carry the other
/// half of those bonds' energy), minimised over the section's unknowns.
double relaxed_energy(const Prism& prism, Mode mode) {
  const Model& m = prism.model;
  const double spacing = m.spec.lattice.spacing;
  const auto& pos = m.particles.position;
  const auto unknowns =
      static_cast<Eigen::Index>(prism.axes.components.size() * prism.cells.size());
  std::vector<std::pair<std::size_t, std::size_t>> bonds; // (particle, directed bond)
  for (std::size_t i : prism.slice) {
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      bonds.emplace_back(i, k);
    }
  }
  // Each particle's displacement, once.
  std::map<std::pair<std::size_t, int>, Affine> field;
  const auto u = [&](std::size_t i, int axis) -> const Affine& {
    const auto key = std::make_pair(i, axis);
    auto it = field.find(key);
    if (it == field.end()) {
      it = field.emplace(key, displacement(prism, mode, i, axis)).first;
    }
    return it->second;
  };
  Eigen::MatrixXd matrix = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(bonds.size()), unknowns);
  Eigen::VectorXd target(static_cast<Eigen::Index>(bonds.size()));
  for (std::size_t row = 0; row < bonds.size(); ++row) {
    const auto [i, k] = bonds[row];
    const std::size_t j = m.family.neighbour[k];
    const double length = 1.0 / m.family.inverse_length[k];
    // Energy density ¼·c_ij V_j·|ξ|·s² with s = ξ·Δu/|ξ|², times the particle volume.
    const double weight =
        std::sqrt(0.25 * bond_stiffness(m, k) * length * m.particles.volume[i]) / (length * length);
    const auto r = static_cast<Eigen::Index>(row);
    double imposed_projection = 0; // ξ·Δu of the imposed field
    for (int axis = 0; axis < m.spec.dimension.dim; ++axis) {
      const double xi = pos[j][axis] - pos[i][axis];
      const Affine& uj = u(j, axis);
      const Affine& ui = u(i, axis);
      imposed_projection += xi * (uj.imposed - ui.imposed);
      for (const auto& [col, c] : uj.terms) {
        matrix(r, col) += weight * xi * c;
      }
      for (const auto& [col, c] : ui.terms) {
        matrix(r, col) -= weight * xi * c;
      }
    }
    target(r) = -weight * imposed_projection;
  }
  // Rigid translations of the section are in the null space; the minimum-norm solution is fine.
  const Eigen::VectorXd relaxed = matrix.completeOrthogonalDecomposition().solve(target);
  const double energy = (matrix * relaxed - target).squaredNorm();
  return energy / (prism.axes.plate ? spacing * spacing : spacing);
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
  const int dim = spec.dimension.dim;
  if (dim < 2) {
    throw std::runtime_error("section_stiffness: needs a 2D or 3D model");
  }
  if (span == depth || span < 0 || depth < 0 || span >= dim || depth >= dim) {
    throw std::runtime_error(
        dim == 2 ? "section_stiffness: span and depth must be the two in-plane axes, x and y"
                 : "section_stiffness: span and depth must be two different axes");
  }
  if (plate && dim == 2) {
    throw std::runtime_error("section_stiffness: a 2D model is a beam (plane stress or strain), "
                             "not a plate");
  }
  Axes ax;
  ax.span = span;
  ax.depth = depth;
  ax.width = 3 - span - depth;
  ax.plate = plate;
  ax.components = dim == 3 && !plate ? std::vector<int>{depth, ax.width} : std::vector<int>{depth};
  const Prism prism = build_prism(spec, body, ax);

  const Material& mat = spec.materials.at(static_cast<std::size_t>(body.material));
  const double e = mat.youngs_modulus * mat.stiffness_factor;
  const double nu = mat.poisson_ratio;
  const double g = e / (2.0 * (1.0 + nu));
  const Box& box = body.region.boxes.front();
  const double h = box.hi[depth] - box.lo[depth];
  const double b = dim == 2 ? spec.dimension.thickness
                   : plate  ? 1.0
                            : box.hi[ax.width] - box.lo[ax.width];
  // The depth is free in every case (σ_depth = 0); what the third axis does sets the modulus of
  // the span direction: free across a 3D beam and in plane stress (E), held in a plate and in
  // plane strain (E/(1 − ν²)).
  const bool held = plate || (dim == 2 && spec.dimension.plane == PlaneMode::plane_strain);
  const double axial = held ? e / (1.0 - nu * nu) : e;

  SectionStiffness out;
  out.section_particles = prism.cells.size();
  out.bending_reference = axial * b * h * h * h / 12.0;
  out.shear_reference = g * b * h;
  out.bending = relaxed_energy(prism, Mode::bending) / (0.5 * out.bending_reference);
  out.shear = relaxed_energy(prism, Mode::shear) / (0.5 * out.shear_reference);
  out.membrane = relaxed_energy(prism, Mode::membrane) / (0.5 * axial * b * h);
  return out;
}

std::string to_string(BeamCase beam) {
  switch (beam) {
  case BeamCase::cantilever_uniform:
    return "cantilever, uniform load";
  case BeamCase::cantilever_tip:
    return "cantilever, tip load";
  case BeamCase::clamped_uniform:
    return "clamped at both ends, uniform load";
  case BeamCase::clamped_centre:
    return "clamped at both ends, centre load";
  case BeamCase::simple_uniform:
    return "simply supported, uniform load";
  case BeamCase::simple_centre:
    return "simply supported, centre load";
  }
  return "?";
}

namespace {

enum class EndHold { free, simple, clamped };

/// What the supports of `spec` do at the end of the body at span coordinate `end`.
EndHold hold_at(const ModelSpec& spec, int span, int depth, double end) {
  const double reach = spec.lattice.spacing;
  EndHold hold = EndHold::free;
  for (const SupportSpec& s : spec.supports) {
    bool near = false;
    for (const Box& b : s.region.boxes) {
      near = near || (b.lo[span] <= end + reach && b.hi[span] >= end - reach);
    }
    if (!near) {
      continue;
    }
    bool all_fixed = true;
    for (int c = 0; c < spec.dimension.dim; ++c) {
      all_fixed = all_fixed && s.fixed[static_cast<std::size_t>(c)];
    }
    if (s.mirror[static_cast<std::size_t>(span)] || all_fixed) {
      hold = EndHold::clamped;
    } else if (s.fixed[static_cast<std::size_t>(depth)] && hold == EndHold::free) {
      hold = EndHold::simple;
    }
  }
  return hold;
}

} // namespace

std::optional<BeamCase> beam_case_of(const ModelSpec& spec, int span, int depth) {
  if (spec.bodies.empty() || spec.loads.empty()) {
    return std::nullopt;
  }
  const Box& body = spec.bodies.front().region.boxes.front();
  const double lo = body.lo[span], hi = body.hi[span], length = hi - lo;
  const EndHold first = hold_at(spec, span, depth, lo), last = hold_at(spec, span, depth, hi);
  // Where the load sits along the span: the extent of all its boxes.
  double from = hi, to = lo;
  for (const LoadSpec& l : spec.loads) {
    for (const Box& b : l.load.region.boxes) {
      from = std::min(from, std::max(b.lo[span], lo));
      to = std::max(to, std::min(b.hi[span], hi));
    }
  }
  const bool uniform = to - from >= 0.9 * length;
  const double centre = 0.5 * (from + to);
  const auto within = [&](double x) {
    return to - from <= 0.2 * length && std::abs(centre - x) <= 0.2 * length;
  };
  const bool cantilever = (first == EndHold::clamped) != (last == EndHold::clamped) &&
                          (first == EndHold::free || last == EndHold::free);
  if (cantilever) {
    const double tip = first == EndHold::free ? lo : hi;
    if (uniform) {
      return BeamCase::cantilever_uniform;
    }
    return within(tip) ? std::optional(BeamCase::cantilever_tip) : std::nullopt;
  }
  const bool clamped = first == EndHold::clamped && last == EndHold::clamped;
  const bool simple = first == EndHold::simple && last == EndHold::simple;
  if (!clamped && !simple) {
    return std::nullopt;
  }
  if (uniform) {
    return clamped ? BeamCase::clamped_uniform : BeamCase::simple_uniform;
  }
  if (within(0.5 * (lo + hi))) {
    return clamped ? BeamCase::clamped_centre : BeamCase::simple_centre;
  }
  return std::nullopt;
}

double timoshenko_shear_ratio(const SectionStiffness& s, BeamCase beam, double span) {
  double alpha = 0;
  switch (beam) {
  case BeamCase::cantilever_uniform:
    alpha = 4.0;
    break;
  case BeamCase::cantilever_tip:
    alpha = 3.0;
    break;
  case BeamCase::clamped_uniform:
  case BeamCase::clamped_centre:
    alpha = 48.0;
    break;
  case BeamCase::simple_uniform:
    alpha = 9.6;
    break;
  case BeamCase::simple_centre:
    alpha = 12.0;
    break;
  }
  return alpha * s.bending_reference / (shear_coefficient * s.shear_reference * span * span);
}

double deflection_factor(const SectionStiffness& s, double shear_ratio) {
  return (1.0 / s.bending + shear_ratio / s.shear) / (1.0 + shear_ratio);
}

} // namespace pd::verification
