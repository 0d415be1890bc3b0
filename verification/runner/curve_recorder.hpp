// The record of a quasi-static case (rc-beam, compression-cube): one CSV row per increment in
// DIR/curve.csv, rewritten atomically after every increment so that an interrupted run keeps the
// curve so far, VTU files of the particles after chosen increments, and how the run went in the
// case's JSON.
#pragma once

#include "libpd/core/atomic_file.hpp"
#include "libpd/core/json.hpp"
#include "libpd/io/output.hpp"
#include "libpd/time/quasi_static.hpp"
#include "verification.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace pd::verification {

class CurveRecorder {
public:
  using Row = std::function<std::string(const Simulation&, const quasi_static::IncrementInfo&)>;

  /// `dir` empty: nothing is written. `vtu_increments` are 1-based increment numbers.
  CurveRecorder(std::filesystem::path dir, const std::string& header,
                std::vector<int> vtu_increments, std::string vtu_prefix, Row row)
      : dir_(std::move(dir)), csv_(header + "\n"), vtu_increments_(std::move(vtu_increments)),
        vtu_prefix_(std::move(vtu_prefix)), row_(std::move(row)) {}

  void operator()(const Simulation& sim, const quasi_static::IncrementInfo& info) {
    csv_ += row_(sim, info) + "\n";
    if (dir_.empty()) {
      return;
    }
    write_file_atomically(dir_ / "curve.csv", csv_);
    for (int v : vtu_increments_) {
      if (v == info.index) {
        write_vtu(dir_ / fmt::format("{}-inc{:03d}.vtu", vtu_prefix_, info.index), sim);
      }
    }
  }

private:
  std::filesystem::path dir_;
  std::string csv_;
  std::vector<int> vtu_increments_;
  std::string vtu_prefix_;
  Row row_;
};

inline std::size_t increments_not_converged(const quasi_static::Outcome& outcome) {
  std::size_t n = 0;
  for (const auto& inc : outcome.increments) {
    n += inc.converged ? 0 : 1;
  }
  return n;
}

/// How an incremental run went, appended to its JSON: increments done and not converged, the
/// largest residual if asked, ADR iterations, whether it completed (else why it stopped) and its
/// wall time.
inline void record_outcome(Json& j, const quasi_static::Outcome& outcome,
                           bool with_largest_residual) {
  j["increments_done"] = outcome.increments.size();
  j["increments_not_converged"] = increments_not_converged(outcome);
  if (with_largest_residual) {
    double worst = 0;
    for (const auto& inc : outcome.increments) {
      worst = std::max(worst, inc.residual);
    }
    j["largest_residual"] = worst;
  }
  j["iterations"] = outcome.iterations; // ADR iterations, or the static solver's Newton ones
  std::size_t events = 0;
  for (const auto& inc : outcome.increments) {
    events += inc.break_events;
  }
  j["break_events"] = events; // static: re-solves after bonds broke
  j["completed"] = outcome.completed;
  if (!outcome.stop_reason.empty()) {
    j["stop_reason"] = outcome.stop_reason;
  }
  j["wall_seconds"] = outcome.wall_seconds;
}

/// The static curve against the ADR curve of the same increments (issue 15): the peaks (the first
/// maximum before a drop of `drop`, as the cases define their peak), their difference, and the
/// largest difference of the two curves up to the later peak, relative to the ADR peak.
inline Json compare_with_adr(const std::vector<double>& adr, const std::vector<double>& stat,
                             const std::vector<double>& x, double drop) {
  auto peak = [&](const std::vector<double>& y) {
    std::size_t at = 0;
    for (std::size_t k = 0; k < y.size(); ++k) {
      if (y[k] > y[at]) {
        at = k;
      } else if (y[k] < (1.0 - drop) * y[at]) {
        break;
      }
    }
    return at;
  };
  Json j;
  if (adr.empty() || stat.empty()) {
    return j;
  }
  const std::size_t pa = peak(adr), ps = peak(stat);
  double worst = 0;
  for (std::size_t k = 0; k <= std::max(pa, ps) && k < std::min(adr.size(), stat.size()); ++k) {
    worst = std::max(worst, std::abs(stat[k] - adr[k]));
  }
  j["adr_peak"] = adr[pa];
  j["adr_peak_at"] = x[pa];
  j["static_peak"] = stat[ps];
  j["static_peak_at"] = x[ps];
  j["peak_difference"] = adr[pa] > 0 ? stat[ps] / adr[pa] - 1.0 : 0.0;
  j["largest_curve_difference_to_peak"] = adr[pa] > 0 ? worst / adr[pa] : 0.0;
  return j;
}

/// Static and ADR solve the same quasi-static problem on the same increments, so their peaks are
/// held to agree within the 5 % the fracture cases are held to (issue 36); the curves' other
/// differences are reported. Writes the gated value into `out` and returns the gate.
inline Gate gate_static_against_adr(Json& out, const Json& comparison) {
  const Gate gate{"static_vs_adr_peak", 0.05};
  // Without two curves there is no difference to write, and the unwritten gate fails the case.
  if (const Json* difference = comparison.find("peak_difference")) {
    out["error"][gate.key] = std::abs(*difference->number());
    out["signed_error"][gate.key] = *difference->number();
  }
  return gate;
}

/// A sensitivity run's peak relative to the main run's (0 if the main run has none).
inline double peak_change(double peak, double main_peak) {
  return main_peak > 0 ? peak / main_peak - 1.0 : 0.0;
}

} // namespace pd::verification
