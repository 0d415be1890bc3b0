#include "observed_order.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace pd::verification {

namespace {

/// Least-squares slope of log|e| against log h.
double fitted_slope(const std::vector<double>& h, const std::vector<double>& e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const auto n = static_cast<double>(h.size());
  for (std::size_t k = 0; k < h.size(); ++k) {
    const double x = std::log(h[k]), y = std::log(std::abs(e[k]));
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

bool usable(double e) {
  return std::isfinite(e) && e != 0.0;
}

} // namespace

ObservedOrder observed_order(std::vector<std::pair<double, double>> spacing_error) {
  // Coarse to fine; stable, so the first of a repeated spacing stays.
  std::stable_sort(spacing_error.begin(), spacing_error.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  spacing_error.erase(std::unique(spacing_error.begin(), spacing_error.end(),
                                  [](const auto& a, const auto& b) { return a.first == b.first; }),
                      spacing_error.end());
  ObservedOrder out;
  out.levels = spacing_error.size();
  // The longest run of falling |error|; ">=" keeps the finer of two equally long runs.
  std::size_t best_first = 0, best_length = 0;
  std::size_t first = 0;
  for (std::size_t k = 0; k < spacing_error.size(); ++k) {
    const double e = spacing_error[k].second;
    const bool falls =
        k > first && usable(e) && std::abs(e) < std::abs(spacing_error[k - 1].second);
    if (!falls) {
      first = k; // a run starts here (if its error can be fitted at all)
    }
    const std::size_t length = usable(spacing_error[first].second) ? k - first + 1 : 0;
    if (length >= 2 && length >= best_length) {
      best_first = first;
      best_length = length;
    }
  }
  out.monotone = best_length >= 2 && best_length == spacing_error.size();
  if (best_length < 2) {
    return out;
  }
  for (std::size_t k = best_first; k < best_first + best_length; ++k) {
    out.spacings.push_back(spacing_error[k].first);
    out.errors.push_back(spacing_error[k].second);
  }
  out.order = fitted_slope(out.spacings, out.errors);
  return out;
}

Json to_json(const ObservedOrder& o) {
  Json j;
  j["order"] = o.order ? Json(*o.order) : Json(nullptr);
  j["spacings"] = Json::array_of(o.spacings);
  j["errors"] = Json::array_of(o.errors);
  j["levels"] = o.levels;
  j["monotone"] = o.monotone;
  j["text"] = o.text();
  return j;
}

std::string ObservedOrder::text() const {
  if (!order) {
    return fmt::format("not monotone (|error| does not fall at any refinement of the {} levels)",
                       levels);
  }
  const std::string range =
      fmt::format("{:.3f} over λ = {:g} … {:g}", *order, spacings.front(), spacings.back());
  if (monotone) {
    return fmt::format("{} ({} levels)", range, spacings.size());
  }
  return fmt::format("{} ({} of {} levels; |error| is not monotone over the others)", range,
                     spacings.size(), levels);
}

} // namespace pd::verification
