// How much memory a run may use, and byte sizes written and read as people write them.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace pd {

struct MemoryBudget {
  double bytes = 0;
  std::string source; ///< "PD_MEMORY_LIMIT" or "MemAvailable in /proc/meminfo"
};

/// Memory a run may use: the environment variable PD_MEMORY_LIMIT if set (bytes, or with a
/// suffix K, M, G, T = powers of 1024, e.g. "2G", "512MiB"), else MemAvailable of /proc/meminfo;
/// nullopt if neither is known. Throws std::invalid_argument for a malformed PD_MEMORY_LIMIT.
std::optional<MemoryBudget> available_memory();

/// "2G" → 2147483648; throws std::invalid_argument for anything that is not a size.
double parse_byte_size(std::string_view text);

/// "48.0 GiB", "512 MiB", "12 KiB", "800 B".
std::string format_bytes(double bytes);

} // namespace pd
