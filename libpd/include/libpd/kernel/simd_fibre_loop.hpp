// The virtual-fibre kernel's two passes (kernel/fibre_kernel.cpp) over Google Highway, on the same
// terms as the bond-based loop (simd_bond_loop.hpp): lanes over the arms of one particle's CSR
// row, each arm rounded exactly as in the scalar kernel (no FMA contraction), each particle's sums
// taken in `virtual_lanes` lanes reduced in lane order. The result depends on neither the thread
// count nor the instruction set; it differs from the scalar kernel only in the order of the
// per-particle sums. Elastic arms only: plasticity and damage run the scalar kernel.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pd::kernel {

/// Raw views of the arrays the two passes read and write.
struct FibreData {
  const std::size_t* offsets = nullptr;
  const std::uint32_t* neighbour = nullptr;
  const double* inverse_length = nullptr;
  const double* mean_weight = nullptr; ///< (1/N) A_k |ξ_k| per directed bond
  const double* own = nullptr;         ///< A_k per directed bond
  const double* other = nullptr;       ///< B_k per directed bond
  const double* shear = nullptr;       ///< G(N+2) per particle
  const double* volumetric = nullptr;  ///< NK − G(N+2) per particle
  double* mean_term = nullptr;         ///< (NK − G(N+2)) ε̄ per particle: pass 1 writes it
};

/// Pass 1 (eq. 73: mean_term of particles [first, last); `b` is not used) or pass 2 (eqs. 70, 77:
/// b of particles [first, last), reading every particle's mean_term). Threads may call either on
/// disjoint ranges; pass 2 must wait for the whole of pass 1.
using FibreRows = void (*)(const FibreData& d, const double* y, double* b, std::size_t first,
                           std::size_t last);

/// The two passes for the best instruction set of this CPU.
FibreRows simd_fibre_mean_rows();
FibreRows simd_fibre_force_rows();

} // namespace pd::kernel
