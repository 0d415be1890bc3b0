// The progress line of a run on stderr (step, time, share of end_time and an ETA), redrawn at
// most twice a second so that it costs nothing beside the steps.
#pragma once

#include "libpd/time/simulation.hpp"

#include <chrono>

namespace pd {

class ProgressLine {
public:
  /// `end_time` ≤ 0: no share nor ETA. Shows nothing unless `enabled`.
  ProgressLine(bool enabled, double end_time);
  void update(const Simulation& sim);
  /// Erase the line, so that what the caller prints next starts clean.
  void clear();

private:
  bool enabled_;
  double end_time_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_ = start_;
};

} // namespace pd
