// See handwritten_simd.cpp.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pd_bench {

struct HandWrittenData {
  const std::size_t* offsets;
  const std::uint32_t* neighbour;
  const double* inverse_length;
  double stiffness;
};

/// Exact-stretch elastic forces of particles [first, last), best instruction set of this CPU.
void hand_written_rows(const HandWrittenData& h, const double* y, double* b, std::size_t first,
                       std::size_t last);

} // namespace pd_bench
