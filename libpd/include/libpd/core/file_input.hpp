// Reading an input file whole, safely: only a regular file (a FIFO or /dev/zero would be read
// forever), only up to a stated size, and every failure with the OS reason.
#pragma once

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace pd {

/// Why an input file was not read; what() is a sentence without the path ("is a FIFO: …").
class FileInputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// The content of `path` if it is a regular file of at most `max_bytes`; FileInputError
/// otherwise (directories, FIFOs, devices and sockets are refused without reading from them).
std::string read_regular_file(const std::filesystem::path& path, std::size_t max_bytes);

/// True if `path` exists and is a regular file whose first bytes are `prefix`.
bool regular_file_starts_with(const std::filesystem::path& path, const std::string& prefix);

} // namespace pd
