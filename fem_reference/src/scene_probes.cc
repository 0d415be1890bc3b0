// The scene's probes on the FE solution (pd-fem --scene): what PD reads, read from the same
// continuum problem at the same places (docs/scenes.md, Probes).
#include "elastic_common.h"
#include "libpd/app/probes.hpp"
#include "scene_reference.h"

#include <algorithm>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/numerics/fe_field_function.h>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace pdfem {
// Why: the force a support exerts on the body is what equilibrium lacks without it: at its
// dofs K u = f + R, so R = K u - f, summed over the dofs of the probe's component (in 2D times
// the thickness: the FE problem is per unit thickness, PD's forces are in N). A moment sums
// (x_i - about) × R_i over all the support's dofs at their support points: with Lagrange shape
// functions (Σ φ_i = 1, Σ x_i φ_i = x) that is exactly the moment of the traction.
template <int dim>
double SceneReference<dim>::reaction(const SceneProbe& probe) const {
  using Q = pd::ProbeSpec::Quantity;
  const bool moment = probe.quantity == Q::moment;
  FEValues<dim> fv(*mapping, fe, quadrature,
                   update_values | update_gradients | update_quadrature_points | update_JxW_values);
  std::set<types::global_dof_index> wanted;
  for (const auto i : support_dofs.at(probe.support))
    if (moment || dof_component[i] == static_cast<unsigned int>(probe.component))
      wanted.insert(i);
  if (wanted.empty())
    throw std::runtime_error(
        "reaction probe '" + probe.name + "': support '" + problem.supports.at(probe.support).name +
        "' does not hold " +
        std::string(pd::probe_component_words.at(static_cast<std::size_t>(probe.component))));
  FullMatrix<double> cell_matrix;
  Vector<double> cell_rhs;
  const unsigned int n = fe.n_dofs_per_cell();
  Vector<double> u(n), r(n);
  std::vector<types::global_dof_index> dofs(n);
  std::map<types::global_dof_index, double> residual;
  for (const auto& cell : dof_handler->active_cell_iterators()) {
    cell->get_dof_indices(dofs);
    if (std::none_of(dofs.begin(), dofs.end(), [&](auto i) { return wanted.count(i) > 0; }))
      continue;
    cell_system(cell, fv, cell_matrix, cell_rhs);
    cell->get_dof_values(solution, u);
    cell_matrix.vmult(r, u);
    for (unsigned int i = 0; i < n; ++i)
      if (wanted.count(dofs[i]))
        residual[dofs[i]] += r(i) - cell_rhs(i);
  }
  double sum = 0.;
  const auto a = static_cast<unsigned int>(probe.component);
  for (const auto& [i, value] : residual) {
    if (!moment) {
      sum += value;
      continue;
    }
    // The axis a's part of (x - about) × R, R = value along the dof's component d.
    const unsigned int d = dof_component[i];
    const unsigned int b = (a + 1) % 3, c = (a + 2) % 3;
    const double arm_b = b < dim ? dof_points[i][b] - probe.about[b] : -probe.about[b];
    const double arm_c = c < dim ? dof_points[i][c] - probe.about[c] : -probe.about[c];
    if (d == c)
      sum += arm_b * value;
    else if (d == b)
      sum -= arm_c * value;
  }
  return dim == 2 ? sum * problem.dimension.thickness : sum;
}

template <int dim>
void SceneReference<dim>::evaluate_probes() {
  using Q = pd::ProbeSpec::Quantity;
  Functions::FEFieldFunction<dim> field(*dof_handler, solution, *mapping);
  auto& values = levels.back().values;
  for (const SceneProbe& probe : problem.probes) {
    if (probe.quantity == Q::reaction || probe.quantity == Q::moment) {
      values.push_back(reaction(probe));
      continue;
    }
    std::vector<Point<dim>> points(probe.points.size());
    for (std::size_t k = 0; k < points.size(); ++k)
      for (unsigned int d = 0; d < dim; ++d)
        points[k][d] = probe.points[k][d];
    double sum = 0.;
    if (probe.quantity == Q::displacement || probe.quantity == Q::opening) {
      std::vector<Vector<double>> u(points.size(), Vector<double>(dim));
      field.vector_value_list(points, u);
      if (probe.quantity == Q::opening) {
        double opening = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          opening += (u[1][d] - u[0][d]) * probe.direction[d];
        values.push_back(opening);
        continue;
      }
      for (const auto& v : u)
        sum += v[probe.component];
    } else {
      std::vector<std::vector<Tensor<1, dim>>> grad(points.size(),
                                                    std::vector<Tensor<1, dim>>(dim));
      field.vector_gradient_list(points, grad);
      const auto& ab = pd::tensor_component_axes[static_cast<std::size_t>(probe.component)];
      for (std::size_t k = 0; k < points.size(); ++k) {
        if (probe.quantity == Q::strain) {
          // ε_ab = ½ (∂u_a/∂x_b + ∂u_b/∂x_a); PD reads no out-of-plane strain in 2D.
          const auto a = static_cast<unsigned int>(ab[0]), b = static_cast<unsigned int>(ab[1]);
          sum += 0.5 * (grad[k][a][b] + grad[k][b][a]);
          continue;
        }
        const auto sigma = stress(probe.points[k], grad[k]);
        sum += probe.quantity == Q::von_mises
                   ? pd::von_mises(sigma)
                   : sigma[static_cast<std::size_t>(ab[0])][static_cast<std::size_t>(ab[1])];
      }
    }
    values.push_back(sum / static_cast<double>(points.size()));
  }
}

// Why: PD's stress probes read σ; here σ = λ tr ε I + 2μ ε of the body's material at x (plane
// stress: λ*; the out-of-plane σ_zz of a 2D model is λ tr ε in plane strain, 0 in plane stress).
template <int dim>
std::array<std::array<double, 3>, 3>
SceneReference<dim>::stress(const pd::Vec3& x, const std::vector<Tensor<1, dim>>& grad) const {
  const int body = problem.body_at(x);
  const pd::Material& m = problem.materials.at(static_cast<std::size_t>(
      problem.bodies.at(static_cast<std::size_t>(std::max(body, 0))).material));
  const LameConstants lame = lame_constants(m.youngs_modulus * m.stiffness_factor, m.poisson_ratio,
                                            problem.plane_stress());
  double trace = 0.;
  for (unsigned int d = 0; d < dim; ++d)
    trace += grad[d][d];
  std::array<std::array<double, 3>, 3> sigma{};
  for (unsigned int a = 0; a < dim; ++a)
    for (unsigned int b = 0; b < dim; ++b)
      sigma[a][b] = lame.mu * (grad[a][b] + grad[b][a]) + (a == b ? lame.lambda * trace : 0.);
  if (dim == 2)
    sigma[2][2] = problem.plane_stress() ? 0. : lame.lambda * trace;
  return sigma;
}

template double SceneReference<2>::reaction(const SceneProbe&) const;
template double SceneReference<3>::reaction(const SceneProbe&) const;
template void SceneReference<2>::evaluate_probes();
template void SceneReference<3>::evaluate_probes();
} // namespace pdfem
