// The virtual-fibre kernel's two passes (kernel/fibre_kernel.cpp) over Google Highway, on the same
// terms as the bond-based loop (simd_bond_loop.hpp): lanes over the arms of one particle's CSR
// row, each arm rounded exactly as in the scalar kernel (no FMA contraction), each particle's sums
// taken in `virtual_lanes` lanes reduced in lane order. The result depends on neither the thread
// count nor the instruction set; it differs from the scalar kernel only in the order of the
// per-particle sums. Elastic arms only: plasticity and damage run the scalar kernel.
//
// The passes are bound by data movement more than by arithmetic (pd-kernel-bench FibreVsBond):
// each particle's position and, for pass 2, its mean term sit together in one padded record, so
// that a neighbour arrives in one 32-byte load. Two things were measured and left out: keeping pass
// 1's arm lengths for pass 2 (the extra stream cost more than the square roots it saved) and
// computing pass 1's weight (1/N) A_k |ξ_k| from A_k instead of reading it (no faster: the
// division it adds competes with the square roots).
#pragma once

#include <cstddef>
#include <cstdint>

namespace pd::kernel {

/// Raw views of the arrays the passes read and write.
struct FibreData {
  const std::size_t* offsets = nullptr;
  const std::uint32_t* neighbour = nullptr;
  const double* inverse_length = nullptr;
  const double* mean_weight = nullptr; ///< (1/N) A_k |ξ_k| per directed bond
  const double* own = nullptr;         ///< A_k per directed bond
  const double* other = nullptr;       ///< B_k per directed bond
  const double* shear = nullptr;       ///< G(N+2) per particle
  const double* volumetric = nullptr;  ///< NK − G(N+2) per particle
  /// (y_0, y_1, y_2, 0) per particle, written by the pack for pass 1, and (y_0, y_1, y_2,
  /// (NK − G(N+2)) ε̄) written by pass 1 for pass 2: a neighbour arrives in one 32-byte load.
  double* record = nullptr;
  double* state = nullptr;
  double* mean_term = nullptr; ///< (NK − G(N+2)) ε̄ per particle: pass 1 writes it
};

/// The pack (`record` of particles [first, last) from y), pass 1 (eq. 73: mean_term and `state` of
/// particles [first, last)) or pass 2 (eqs. 70, 77: b of particles [first, last), reading every
/// particle's `state`); `b` is used by pass 2 only. Threads may call each on disjoint ranges; each
/// must wait for the whole of the one before.
using FibreRows = void (*)(const FibreData& d, const double* y, double* b, std::size_t first,
                           std::size_t last);

/// The two passes for the best instruction set of this CPU.
FibreRows simd_fibre_pack_rows();
FibreRows simd_fibre_mean_rows();
/// `uniform_shear`: every particle's G(N+2) is shear[0] (one material), so pass 2 gathers none.
FibreRows simd_fibre_force_rows(bool uniform_shear);

} // namespace pd::kernel
