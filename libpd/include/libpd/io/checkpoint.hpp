// Checkpoint files: the complete state of a run in one binary file, so that a run stopped at any
// point (SIGKILL, Ctrl-C, a batch-queue limit) and restarted from its last checkpoint ends bitwise
// identical to a run that was never stopped.
//
// Layout (native byte order; a marker refuses files from a machine of the other order):
//
//   magic "LIBPDCKP" (8 bytes) · format version u32 · byte-order marker u32
//   fingerprint length u64 · fingerprint (count u32, then key/value strings)
//   payload length u64 · payload (tagged sections written by Simulation, Integrator and run_scene;
//   per-particle and per-bond values are those of the particles the writing rank owns, keyed by
//   global index in the KEYS section, so a set restarts on any number of ranks)
//   FNV-1a-64 checksum u64 of every byte before it
//
// The fingerprint names what makes the run (particles, bonds, Δt, integrator, a hash of the model's
// arrays, ...): a checkpoint is only restored into a run whose fingerprint is equal, and a refusal
// names the keys that differ. The checksum catches truncated and corrupted files, which are refused
// before anything is read from them. Files are written atomically (temporary file in the same
// folder, fsync, rename, fsync of the folder), so a reader sees the old checkpoint or the complete
// new one even if the writer is killed mid-write.
#pragma once

#include "libpd/core/binary_state.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pd {

/// What makes a run, as ordered key/value text ("particles" → "1200", "dt" → "4.452e-07", ...).
/// `scene` is only reported, never compared: a scene file may be moved or renamed.
struct CheckpointFingerprint {
  std::string scene;
  std::vector<std::pair<std::string, std::string>> items;

  void add(std::string key, std::string value) {
    items.emplace_back(std::move(key), std::move(value));
  }
  const std::string* find(std::string_view key) const;
};

/// Write a checkpoint atomically: temporary file beside `path`, fsync, rename, fsync of the folder.
void write_checkpoint(const std::filesystem::path& path, const CheckpointFingerprint& fingerprint,
                      const CheckpointWriter& payload);

/// True if `path` is a regular file that starts with the checkpoint magic bytes: the only kind of
/// existing file a checkpoint may replace.
bool is_checkpoint_file(const std::filesystem::path& path);

/// Read and check a checkpoint: magic, version, byte order, size and checksum, then the
/// fingerprint against `expected`. Returns a reader positioned at the start of the payload.
/// Throws CheckpointError with a one-line reason otherwise.
CheckpointReader read_checkpoint(const std::filesystem::path& path,
                                 const CheckpointFingerprint& expected);

/// The pieces of a set written by a run split over ranks, each checked as read_checkpoint does;
/// the reader assembles this process's values from them (CheckpointReader::keys).
CheckpointReader read_checkpoint_set(const std::vector<std::filesystem::path>& pieces,
                                     const CheckpointFingerprint& expected);

/// Only the fingerprint of a checkpoint (after the integrity checks), e.g. to print it.
CheckpointFingerprint read_checkpoint_fingerprint(const std::filesystem::path& path);

/// A double as the shortest text that reads back to the same bits, so fingerprints compare bit
/// patterns and stay readable in messages.
std::string exact_text(double v);

} // namespace pd
