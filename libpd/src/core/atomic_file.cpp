#include "libpd/core/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace pd {

void write_file_atomically(const std::filesystem::path& path, const std::string& content) {
  if (path.has_parent_path()) {
    std::filesystem::create_directories(path.parent_path());
  }
  const std::filesystem::path tmp =
      path.string() + fmt::format(".tmp-{}", static_cast<long>(::getpid()));
  try {
    {
      errno = 0;
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) {
        throw std::runtime_error(
            fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno)));
      }
      out << content;
      out.flush();
      if (!out) {
        throw std::runtime_error(
            fmt::format("error while writing {}: {}", tmp.string(), std::strerror(errno)));
      }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
      throw std::runtime_error(
          fmt::format("cannot rename {} to {}: {}", tmp.string(), path.string(), ec.message()));
    }
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored); // never leave a stray temporary behind
    throw;
  }
}

} // namespace pd
