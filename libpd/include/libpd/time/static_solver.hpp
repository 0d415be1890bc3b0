// The linear system of solver.integrator: static (time/static_solver.cpp), for tests and tools
// that check it: K u = f on the free unknowns, the supports substituted, in force units (each
// equation of particle i times its volume V_i, so that Rᵀ K R is symmetric also where volumes
// differ).
#pragma once

#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <vector>

namespace pd {

/// K in compressed rows (columns sorted within a row) and the right-hand side f.
struct StaticSystem {
  std::vector<std::size_t> unknowns; ///< the global dof 3i + c of each unknown, ascending
  std::vector<int> row_offsets;      ///< n + 1
  std::vector<int> columns;          ///< nnz
  std::vector<double> values;        ///< nnz
  std::vector<double> rhs;           ///< f = V (b_ext − K_fp u_p), n

  std::size_t size() const { return unknowns.size(); }
  /// y = K x (n values each).
  void multiply(const double* x, double* y) const;
  /// ‖K − Kᵀ‖_F / ‖K‖_F.
  double asymmetry() const;
};

/// Assemble the linearised stiffness at the reference configuration (bonds broken by damage left
/// out) with the model's supports substituted: prescribed values to the right-hand side, mirror
/// dependants' columns onto their masters (and, under consistent coupling, their rows too).
StaticSystem assemble_static_system(const Model& model);

} // namespace pd
