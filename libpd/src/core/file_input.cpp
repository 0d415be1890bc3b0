// Reading input files whole, safely.
#include "libpd/core/file_input.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

namespace pd {

namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) {
    return "a directory";
  }
  if (S_ISFIFO(mode)) {
    return "a FIFO (named pipe)";
  }
  if (S_ISCHR(mode)) {
    return "a character device";
  }
  if (S_ISBLK(mode)) {
    return "a block device";
  }
  if (S_ISSOCK(mode)) {
    return "a socket";
  }
  return "not a regular file";
}

/// Closes the descriptor on every path out.
struct Descriptor {
  int fd;
  ~Descriptor() {
    if (fd >= 0) {
      ::close(fd);
    }
  }
};

} // namespace

std::string read_regular_file(const std::filesystem::path& path, std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever.
  Descriptor d{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (d.fd < 0) {
    throw FileInputError(fmt::format("cannot be opened: {}", std::strerror(errno)));
  }
  struct stat st {};
  if (::fstat(d.fd, &st) != 0) {
    throw FileInputError(fmt::format("cannot be examined: {}", std::strerror(errno)));
  }
  if (!S_ISREG(st.st_mode)) {
    throw FileInputError(fmt::format("is {}; only regular files are read", kind_of(st.st_mode)));
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size > max_bytes) {
    throw FileInputError(
        fmt::format("is {} bytes, more than the {} bytes accepted here", size, max_bytes));
  }
  std::string content(size, '\0');
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(d.fd, content.data() + done, size - done);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n < 0) {
      throw FileInputError(fmt::format("cannot be read: {}", std::strerror(errno)));
    }
    if (n == 0) {
      break; // shrank while being read: take what is there
    }
    done += static_cast<std::size_t>(n);
  }
  content.resize(done);
  return content;
}

bool regular_file_starts_with(const std::filesystem::path& path, const std::string& prefix) {
  Descriptor d{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  struct stat st {};
  if (d.fd < 0 || ::fstat(d.fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    return false;
  }
  std::string head(prefix.size(), '\0');
  return ::read(d.fd, head.data(), head.size()) == static_cast<ssize_t>(head.size()) &&
         head == prefix;
}

} // namespace pd
