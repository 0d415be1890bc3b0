// Files that survive interruption: written to a temporary name in the same folder and renamed
// into place, so a reader sees either the old file or the complete new one, never a truncated one.
#pragma once

#include <filesystem>
#include <string>

namespace pd {

/// Write `content` to `path` atomically (temporary file in the same folder, then rename).
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

} // namespace pd
