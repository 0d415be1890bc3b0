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

#include <cstddef>
#include <vector>

namespace pd {

/// Dependent particles whose displacement is a fixed linear combination of other particles'
/// displacements, the same in every component up to a sign: u_d,c = ±Σ_k a_k u_{s_k},c. Ghost
/// layers outside free surfaces and the particles of a quadratically extrapolated clamp are of this
/// kind (discretisation/ghost_layers.hpp). Sources are never dependants themselves, so one pass
/// sets every dependant and one pass of the transpose folds their forces back.
struct ExtrapolatedParticles {
  std::vector<std::uint32_t> particle; ///< the dependants, ascending
  std::vector<std::size_t> offsets{0}; ///< terms of dependant d: [offsets[d], offsets[d + 1])
  std::vector<std::uint32_t> source;
  std::vector<double> coefficient;
  /// Per dependant, bit c set: component c takes the combination negated (the normal component
  /// of a symmetry image). Empty: no component is negated.
  std::vector<std::uint8_t> negated;

  /// ±1: the sign component c of dependant d takes.
  double sign(std::size_t d, std::size_t c) const {
    return negated.empty() || ((negated[d] >> c) & 1U) == 0 ? 1.0 : -1.0;
  }

  std::size_t size() const { return particle.size(); }
  bool empty() const { return particle.empty(); }
};

} // namespace pd
