// The raw views the bond loops read and write: shared by the scalar template (force_kernel.hpp)
// and the vectorised loop (simd_bond_loop.hpp), so neither header needs the other.
#pragma once

#include "libpd/discretisation/model.hpp"

#include <cstddef>
#include <cstdint>

namespace pd {

/// Bond parameters read either from one uniform value or from per-bond arrays.
struct UniformField {
  static constexpr bool per_bond = false;
};
struct PerBondField {
  static constexpr bool per_bond = true;
};

/// Raw views of the arrays the loop touches.
struct KernelData {
  std::size_t particles = 0;
  const std::size_t* offsets = nullptr;
  const std::uint32_t* neighbour = nullptr;
  const double* inverse_length = nullptr;
  double stiffness = 0;
  double critical_stretch = no_limit;
  double yield_stretch = no_limit;
  const double* bond_stiffness = nullptr;
  const double* bond_critical_stretch = nullptr;
  const double* bond_yield_stretch = nullptr;
  std::uint8_t* broken = nullptr;
  double* plastic_stretch = nullptr;
  double* damage = nullptr;
};

} // namespace pd
