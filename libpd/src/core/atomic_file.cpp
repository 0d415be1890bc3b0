#include "libpd/core/atomic_file.hpp"

#include <array>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <random>
#include <stdexcept>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

namespace pd {

namespace {

/// Closes a descriptor on every path out.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) {
      ::close(fd);
    }
  }
};

/// Twelve random letters and digits: a temporary name nobody can plant a link under in advance.
std::string random_suffix() {
  static constexpr char alphabet[] =
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  std::array<unsigned char, 12> bytes{};
  if (::getrandom(bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size())) {
    std::random_device rd; // getrandom is unavailable only on very old kernels
    for (auto& b : bytes) {
      b = static_cast<unsigned char>(rd());
    }
  }
  std::string s;
  for (const unsigned char b : bytes) {
    s += alphabet[b % (sizeof alphabet - 1)];
  }
  return s;
}

void write_all(int fd, const std::string& s, const std::filesystem::path& tmp) {
  std::size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
    if (n < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw std::runtime_error(
          fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno)));
    }
    done += static_cast<std::size_t>(n);
  }
}

} // namespace

int open_folder(const std::filesystem::path& dir) {
  const std::filesystem::path d = dir.empty() ? std::filesystem::path(".") : dir;
  std::error_code ec;
  std::filesystem::create_directories(d, ec); // an error shows in the open below
  return ::open(d.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
}

void write_file_atomically(const std::filesystem::path& path, const std::string& content,
                           Durability durability) {
  const std::filesystem::path dir = path.parent_path();
  const std::string name = path.filename().string();
  Fd folder{open_folder(dir)};
  if (folder.fd < 0) {
    throw std::runtime_error(fmt::format("cannot write {}: folder {}: {}", path.string(),
                                         dir.empty() ? "." : dir.string(), std::strerror(errno)));
  }
  std::string tmp_name;
  Fd out;
  // O_EXCL fails on any existing name, a dangling link included: the file is the run's own.
  for (int attempt = 0; attempt < 100 && out.fd < 0; ++attempt) {
    tmp_name = name + ".tmp-" + random_suffix();
    out.fd = ::openat(folder.fd, tmp_name.c_str(),
                      O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (out.fd < 0 && errno != EEXIST) {
      break;
    }
  }
  const std::filesystem::path tmp = dir / tmp_name;
  if (out.fd < 0) {
    throw std::runtime_error(
        fmt::format("cannot create {}: {}", tmp.string(), std::strerror(errno)));
  }
  try {
    write_all(out.fd, content, tmp);
    // The data must be on disk before the rename makes it the file: otherwise a power cut could
    // leave a renamed but empty file in place of the previous good one.
    if (durability == Durability::synced && ::fsync(out.fd) != 0) {
      throw std::runtime_error(
          fmt::format("fsync of {} failed: {}", tmp.string(), std::strerror(errno)));
    }
    if (::close(std::exchange(out.fd, -1)) != 0) {
      throw std::runtime_error(
          fmt::format("error while writing {}: {}", tmp.string(), std::strerror(errno)));
    }
    // rename replaces a link planted under `name` by the file; it never writes through it.
    if (::renameat(folder.fd, tmp_name.c_str(), folder.fd, name.c_str()) != 0) {
      throw std::runtime_error(fmt::format("cannot rename {} to {}: {}", tmp.string(),
                                           path.string(), std::strerror(errno)));
    }
  } catch (...) {
    ::unlinkat(folder.fd, tmp_name.c_str(), 0); // never leave a stray temporary behind
    throw;
  }
  if (durability == Durability::synced) {
    ::fsync(folder.fd); // makes the rename itself durable
  }
}

} // namespace pd
