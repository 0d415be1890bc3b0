// The progress line of a run on stderr.
#include "libpd/app/progress.hpp"

#include <cstdio>
#include <fmt/format.h>
#include <string>

namespace pd {

ProgressLine::ProgressLine(bool enabled, double end_time)
    : enabled_(enabled), end_time_(end_time) {}

void ProgressLine::update(const Simulation& sim) {
  const auto now = std::chrono::steady_clock::now();
  if (!enabled_ || now - last_ <= std::chrono::milliseconds(500)) {
    return;
  }
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double t = sim.state().time;
  std::string eta;
  if (end_time_ > 0 && t > 0) {
    eta = fmt::format(" ({:4.1f} %, ETA {:.0f} s)", 100.0 * t / end_time_,
                      elapsed * (end_time_ / t - 1.0));
  }
  fmt::print(stderr, "\r  step {:>9}  t = {:.4g} s{}   ", sim.state().step, t, eta);
}

void ProgressLine::clear() {
  if (enabled_) {
    fmt::print(stderr, "\r{:80}\r", "");
  }
}

} // namespace pd
