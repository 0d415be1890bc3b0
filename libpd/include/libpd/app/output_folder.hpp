// The output folder of a run, claimed before any work: created and proven writable at once
// (not found unwritable after hours), locked so that two runs cannot mix their files, and listed
// in a manifest so that a rerun neither leaves the previous run's files beside its own nor
// deletes anything that is not a run's.
#pragma once

#include <cstdint>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

namespace pd {

/// Why a run may not use its output folder or checkpoint path; what() says what to do.
class OutputFolderError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// What a run writes into its folder, by name: files a checkpoint may never replace and files
/// that mark the folder as holding a run.
bool is_run_output_name(const std::string& name);

class OutputFolder {
public:
  /// The manifest's name: the files the run wrote, one per line.
  static constexpr const char* manifest_name = "manifest.txt";
  static constexpr const char* lock_name = ".pd-lock";

  /// Claims `dir` (created if missing) for this process until destruction. Refuses
  /// (OutputFolderError) a folder that cannot be written, one another pd run holds, and one
  /// with another run's files — unless `overwrite`, which first removes exactly the files its
  /// manifest lists; files of a run without a manifest are never removed. `continuing`: a
  /// restart, which continues the manifest of the run it restarts.
  OutputFolder(std::filesystem::path dir, bool overwrite, bool continuing);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  /// Records that the run wrote `path` (inside the folder); the manifest on disk is updated when
  /// a name is new, so an interrupted run's manifest is complete.
  void add(const std::filesystem::path& path);
  /// Refuses (OutputFolderError) a run whose output would not fit: `bytes` against the space
  /// left on the folder's file system. Returns a warning when it fits tightly, else empty.
  std::string check_space(std::uint64_t bytes) const;

private:
  void write_manifest() const;

  std::filesystem::path dir_;
  int lock_fd_ = -1;
  std::set<std::string> files_;
};

/// Refuses (OutputFolderError) a checkpoint path that would destroy something: an existing file
/// that is not a libpd checkpoint (a scene, /dev/null, a FIFO), or a name the run itself writes
/// in its output folder (summary.json, probes.csv, …).
void check_checkpoint_target(const std::filesystem::path& checkpoint,
                             const std::filesystem::path& output_dir);

} // namespace pd
