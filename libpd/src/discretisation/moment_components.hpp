// Private to libpd's discretisation: the components of the symmetric moment tensors that the
// weight fits (fitted_weights.cpp, gradient_weights.cpp) write one equation for each.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace pd::detail {

/// The symmetric components (index tuples a ≤ b ≤ ..., lexicographic) of an order-k tensor in
/// `dim` dimensions, k ≤ 6; the entries beyond k are 0.
inline std::vector<std::array<std::size_t, 6>> symmetric_components(int dim, std::size_t order) {
  std::vector<std::array<std::size_t, 6>> out;
  std::array<std::size_t, 6> t{};
  const auto n = static_cast<std::size_t>(dim);
  const auto recurse = [&](auto&& self, std::size_t depth, std::size_t from) -> void {
    if (depth == order) {
      out.push_back(t);
      return;
    }
    for (std::size_t a = from; a < n; ++a) {
      t[depth] = a;
      self(self, depth + 1, a);
    }
  };
  recurse(recurse, 0, 0);
  return out;
}

} // namespace pd::detail
