// Stretch measures (Miranda et al. 2019, §2.2–2.3).
//
// A stretch measure turns a deformed bond vector Δy = y_j − y_i (r² = |Δy|²) and the reference
// length L = |ξ| into a scalar stretch and the factor that scales Δy into the force direction:
//   force vector on i = f(stretch) · direction_scale · Δy.
//
//  exact     s  = (r − L)/L                          (eq. 6),  direction Δy/r          (eq. 5)
//  modified  s̄  = (r² − L²)/(2L²)                    (eq. 17), direction Δy/r          (eq. 5)
//  fast      s̄  = (r² − L²)/(2L²)                    (eq. 17), direction Δy/L  — no square root
//
// All three have the same linearisation at Δy = ξ (eqs. 19–22), hence the same micromodulus
// C = c ξ⊗ξ/|ξ|³ (Appendix A), the same elastic constants and the same stable time step (eq. 31).
// At finite stretch they differ: s̄ = s + s²/2 (eq. 26), so at s = 0.1 the modified stretch is 5 %
// larger, and `fast` additionally scales the force by r/L = 1 + s. Use `exact` for large
// deformations; the others are accurate where bonds break or yield at small stretch.
#pragma once

#include "libpd/core/names.hpp"

#include <cmath>
#include <concepts>
#include <string_view>

namespace pd {

struct StretchResult {
  double stretch;
  double direction_scale;
};

template <class S>
concept StretchMeasure = requires(double r2, double inv_len) {
  { S::evaluate(r2, inv_len) } -> std::same_as<StretchResult>;
  { S::bond_energy(r2, inv_len) } -> std::same_as<double>;
  { S::bond_energy(r2, inv_len, r2) } -> std::same_as<double>;
  { S::name } -> std::convertible_to<std::string_view>;
};

struct ExactStretch {
  static constexpr std::string_view name = "exact";
  static StretchResult evaluate(double r2, double inv_len) {
    const double r = std::sqrt(r2);
    return {r * inv_len - 1.0, 1.0 / r};
  }
  /// Energy per unit c of a linear bond with plastic stretch ŝ: w/c = L (s − ŝ)²/2; its derivative
  /// in r is s − ŝ (force c(s − ŝ), eq. 14).
  static double bond_energy(double r2, double inv_len, double plastic = 0.0) {
    const double e = std::sqrt(r2) * inv_len - 1.0 - plastic;
    return 0.5 * e * e / inv_len;
  }
};

struct ModifiedStretch {
  static constexpr std::string_view name = "modified";
  static StretchResult evaluate(double r2, double inv_len) {
    return {0.5 * (r2 * inv_len * inv_len - 1.0), 1.0 / std::sqrt(r2)};
  }
  /// The force c(s̄(r) − ŝ) is central, so its potential is ∫_{r_p}^{r} c(s̄ − ŝ) dr' with s̄(r_p) =
  /// ŝ, r_p = L√(1 + 2ŝ): w/c = (r − r_p)²(r + 2r_p)/(6L²). Written in this factored form, not as
  /// r³/3 − L²r + 2L³/3, because the expanded form cancels catastrophically at small stretch.
  static double bond_energy(double r2, double inv_len, double plastic = 0.0) {
    const double r = std::sqrt(r2);
    const double rp = std::sqrt(1.0 + 2.0 * plastic) / inv_len;
    return (r - rp) * (r - rp) * (r + 2.0 * rp) * inv_len * inv_len / 6.0;
  }
};

struct FastStretch {
  static constexpr std::string_view name = "fast";
  static StretchResult evaluate(double r2, double inv_len) {
    return {0.5 * (r2 * inv_len * inv_len - 1.0), inv_len};
  }
  /// Force c(s̄ − ŝ)·Δy/L derives from w = c L (s̄ − ŝ)²/2 (∂s̄/∂Δy = Δy/L²).
  static double bond_energy(double r2, double inv_len, double plastic = 0.0) {
    const double e = 0.5 * (r2 * inv_len * inv_len - 1.0) - plastic;
    return 0.5 * e * e / inv_len;
  }
};

static_assert(StretchMeasure<ExactStretch>);
static_assert(StretchMeasure<ModifiedStretch>);
static_assert(StretchMeasure<FastStretch>);

enum class StretchKind { exact, modified, fast };

template <>
struct EnumName<StretchKind> {
  static constexpr NameTable<StretchKind, 3> table{{
      {"exact", StretchKind::exact, "s = (r − L)/L (eq. 6)"},
      {"modified", StretchKind::modified, "s̄ = (r² − L²)/(2L²) (eq. 17)"},
      {"fast", StretchKind::fast, "s̄ of eq. 17 with direction Δy/L: no square root"},
  }};
};

} // namespace pd
