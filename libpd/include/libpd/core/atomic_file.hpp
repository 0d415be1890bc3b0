// Files that survive interruption and cannot be turned against their writer: written to a new
// temporary name in the same folder and renamed into place, so a reader sees either the old file
// or the complete new one, never a truncated one. Every name is opened relative to the folder's
// descriptor without following a symbolic link, and the temporary name is unpredictable and
// created exclusively: a link planted in the folder (under the file's name or any temporary
// name) is never written through, so nothing outside the folder can be truncated by a run.
#pragma once

#include <filesystem>
#include <string>

namespace pd {

/// How far `write_file_atomically` makes the file safe against a power cut.
enum class Durability {
  /// Renamed into place: safe against the writer being killed.
  renamed,
  /// Data fsync'ed before the rename and the folder after it: safe against a power cut too.
  synced,
};

/// Write `content` to `path` atomically (exclusive temporary file in the same folder, then
/// rename). Throws std::runtime_error naming the path and the reason.
void write_file_atomically(const std::filesystem::path& path, const std::string& content,
                           Durability durability = Durability::renamed);

/// A descriptor of the folder `dir` (opened O_DIRECTORY, the folder created if missing); -1
/// with errno set if it cannot be opened.
int open_folder(const std::filesystem::path& dir);

} // namespace pd
