// The observed order of convergence of a case's error against the lattice spacing, for the
// accuracy-vs-time sweeps (pd verify CASE-sweep).
//
// A least-squares slope of log|error| against log(spacing) means something only where refining
// lowers the error: a fit through levels where it rises, or where it changes sign (PD stiff at one
// spacing and soft at the next), reports a number that no refinement would follow. So the levels
// are ordered from coarse to fine and the order is fitted over the longest run of consecutive
// levels along which |error| falls at every refinement (between runs of the same length, the finer
// one: nearer the asymptotic range). With no such pair of levels the error is "not monotone".
#pragma once

#include "libpd/core/json.hpp"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace pd::verification {

struct ObservedOrder {
  std::optional<double> order;  ///< slope of log|e| against log h over `spacings`; empty: none
  std::vector<double> spacings; ///< the levels of the fit, coarsest first
  std::vector<double> errors;   ///< their errors
  std::size_t levels = 0;       ///< all levels given (distinct spacings)
  bool monotone = false;        ///< |error| falls at every refinement over all the levels

  /// "1.93 over λ = 0.1 … 0.05 (3 levels)", with "of N" and "not monotone beyond" when levels
  /// were left out; "not monotone (…)" when no refinement lowers the error.
  std::string text() const;
};

/// The observed order from (spacing, error) pairs in any order; the first pair of a repeated
/// spacing is kept. A zero or non-finite error ends a run (its logarithm is no level of a fit).
ObservedOrder observed_order(std::vector<std::pair<double, double>> spacing_error);

/// The case JSON's `observed_order`: order (null when not monotone), spacings and errors of the
/// fit, levels, monotone, text.
Json to_json(const ObservedOrder& o);

} // namespace pd::verification
