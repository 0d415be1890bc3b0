#include "libpd/core/memory.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <fstream>
#include <stdexcept>
#include <string>

namespace pd {

double parse_byte_size(std::string_view text) {
  std::string_view t = text;
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.front())) != 0) {
    t.remove_prefix(1);
  }
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back())) != 0) {
    t.remove_suffix(1);
  }
  double value = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec != std::errc{} || end == t.data() || !std::isfinite(value) || value < 0) {
    throw std::invalid_argument(fmt::format("'{}' is not a size in bytes", text));
  }
  std::string suffix(end, t.data() + t.size());
  std::transform(suffix.begin(), suffix.end(), suffix.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (suffix.ends_with("IB")) {
    suffix.erase(suffix.size() - 2);
  } else if (suffix.size() > 1 && suffix.ends_with("B")) {
    suffix.pop_back();
  }
  static constexpr std::string_view units = "KMGT";
  if (suffix.empty() || suffix == "B") {
    return value;
  }
  const auto pos = units.find(suffix);
  if (suffix.size() != 1 || pos == std::string_view::npos) {
    throw std::invalid_argument(
        fmt::format("'{}' is not a size in bytes (suffixes: K, M, G, T)", text));
  }
  return value * std::pow(1024.0, static_cast<double>(pos + 1));
}

std::optional<MemoryBudget> available_memory() {
  if (const char* limit = std::getenv("PD_MEMORY_LIMIT"); limit != nullptr && *limit != '\0') {
    try {
      return MemoryBudget{parse_byte_size(limit), "PD_MEMORY_LIMIT"};
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("PD_MEMORY_LIMIT: {}", e.what()));
    }
  }
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kib = 0;
  std::string unit;
  while (meminfo >> key >> kib) {
    std::getline(meminfo, unit);
    if (key == "MemAvailable:") {
      return MemoryBudget{kib * 1024.0, "MemAvailable in /proc/meminfo"};
    }
  }
  return std::nullopt;
}

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) {
    return "more than 10^308 B";
  }
  static constexpr std::array<std::string_view, 7> units{"B",   "KiB", "MiB", "GiB",
                                                         "TiB", "PiB", "EiB"};
  std::size_t u = 0;
  while (bytes >= 1024 && u + 1 < units.size()) {
    bytes /= 1024;
    ++u;
  }
  if (u == 0) {
    return fmt::format("{:.0f} B", bytes);
  }
  return bytes < 10 ? fmt::format("{:.1f} {}", bytes, units[u])
                    : fmt::format("{:.3g} {}", bytes, units[u]);
}

} // namespace pd
