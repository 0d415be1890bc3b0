// One constraint of a support on one component of one particle (SupportSpec, model.hpp). Its own
// header so that the mirror coupling (mirror_constraints.hpp), which model.hpp includes, can read
// constraints without including the model.
#pragma once

#include <cstdint>
#include <limits>

namespace pd {

/// A prescribed displacement of one component of one particle. With a load ramp the value is
/// reached gradually, u = F(t)·value (Miranda §3.2 step 14). A mirror constraint instead copies
/// the displacement of another particle's same component, times ±1 (SupportSpec::mirror).
struct Constraint {
  static constexpr std::uint32_t no_mirror = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t particle = 0;
  std::uint8_t component = 0;
  double value = 0;
  std::uint32_t mirror_of = no_mirror; ///< source particle of a mirror constraint
  double mirror_sign = 0;              ///< u = mirror_sign · u(source)
};

} // namespace pd
