// Bond laws: the scalar force of a bond as a function of its stretch (force per unit volume
// squared, divided by the micromodulus c — c and the neighbour volume are applied by the kernel).
//
// Each law is a small policy: `force(s, state)` gives f/c and updates the bond's history if it has
// one. The laws know nothing about neighbour loops, storage or stretch measures; damage (eq. 9–13)
// is an independent axis applied by the kernel, so every law can also break.
#pragma once

#include <concepts>
#include <string_view>

namespace pd {

template <class L>
concept BondLaw = requires(double s, double yield, double& plastic) {
  { L::has_history } -> std::convertible_to<bool>;
  { L::force(s, yield, plastic) } -> std::same_as<double>;
  { L::name } -> std::convertible_to<std::string_view>;
};

/// Linear micro-elastic bond, f = c s (Miranda eq. 7).
struct MicroElastic {
  static constexpr std::string_view name = "elastic";
  static constexpr bool has_history = false;
  static double force(double s, double /*yield*/, double& /*plastic*/) { return s; }
};

/// Micro-plastic bond (Miranda eqs. 14–16, after Macek & Silling 2007): f = c (s − ŝ), where the
/// plastic stretch ŝ follows s whenever the elastic part |s − ŝ| would exceed the yield stretch
/// s_Y, so the bond force is capped at f_Y = c s_Y (perfect plasticity, eq. 16).
struct MicroPlastic {
  static constexpr std::string_view name = "plastic";
  static constexpr bool has_history = true;
  static double force(double s, double yield, double& plastic) {
    double elastic = s - plastic;
    if (elastic > yield) {
      plastic = s - yield;
      elastic = yield;
    } else if (elastic < -yield) {
      plastic = s + yield;
      elastic = -yield;
    }
    return elastic;
  }
};

static_assert(BondLaw<MicroElastic>);
static_assert(BondLaw<MicroPlastic>);

} // namespace pd
