// Checkpoint files: the complete state of a run in one binary file, so that a run stopped at any
// point (SIGKILL, Ctrl-C, a batch-queue limit) and restarted from its last checkpoint ends bitwise
// identical to a run that was never stopped.
//
// Layout (native byte order; a marker refuses files from a machine of the other order):
//
//   magic "LIBPDCKP" (8 bytes) · format version u32 · byte-order marker u32
//   fingerprint length u64 · fingerprint (count u32, then key/value strings)
//   payload length u64 · payload (tagged sections written by Simulation, Integrator and run_scene)
//   FNV-1a-64 checksum u64 of every byte before it
//
// The fingerprint names what makes the run (particles, bonds, Δt, integrator, a hash of the model's
// arrays, ...): a checkpoint is only restored into a run whose fingerprint is equal, and a refusal
// names the keys that differ. The checksum catches truncated and corrupted files, which are refused
// before anything is read from them. Files are written atomically (temporary file in the same
// folder, fsync, rename, fsync of the folder), so a reader sees the old checkpoint or the complete
// new one even if the writer is killed mid-write.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace pd {

/// A checkpoint that cannot be read or does not belong to this run. The message says which file and
/// why, in one line.
class CheckpointError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

inline constexpr std::uint32_t checkpoint_format_version = 1;

/// FNV-1a, 64 bit (Fowler–Noll–Vo): the file checksum and the model hash. Not cryptographic; it
/// detects accidental damage and unequal inputs, which is all a checkpoint needs.
class Fnv1a {
public:
  void add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) {
      hash_ = (hash_ ^ p[k]) * 0x100000001b3ULL;
    }
  }
  template <class T>
  void add_vector(const std::vector<T>& v) {
    const std::uint64_t n = v.size();
    add(&n, sizeof n);
    if (!v.empty()) {
      add(v.data(), v.size() * sizeof(T));
    }
  }
  template <class T>
  void add_value(const T& v) {
    add(&v, sizeof v);
  }
  std::uint64_t value() const { return hash_; }

private:
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;
};

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

/// Binary payload builder. Sections start with a four-letter tag so that a reader out of step
/// fails at once with the section's name instead of misreading numbers.
class CheckpointWriter {
public:
  void section(std::string_view tag);
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void boolean(bool v) { u64(v ? 1 : 0); }
  void string(std::string_view s);
  void doubles(const std::vector<double>& v);
  void bytes(const std::vector<std::uint8_t>& v);
  const std::string& data() const { return data_; }

private:
  void raw(const void* p, std::size_t n) { data_.append(static_cast<const char*>(p), n); }
  std::string data_;
};

/// Reads what CheckpointWriter wrote, in the same order. Every read is bounds-checked; a mismatch
/// throws CheckpointError naming the file and the section.
class CheckpointReader {
public:
  CheckpointReader(std::string data, std::string file)
      : data_(std::move(data)), file_(std::move(file)) {}
  void section(std::string_view tag);
  std::uint64_t u64();
  double f64();
  bool boolean() { return u64() != 0; }
  std::string string();
  std::vector<double> doubles();
  std::vector<std::uint8_t> bytes();
  /// Read a vector of doubles that must have `size` entries (the model's size is fixed).
  std::vector<double> doubles(std::size_t size, std::string_view what);
  std::vector<std::uint8_t> bytes(std::size_t size, std::string_view what);
  /// Throws unless every byte has been read.
  void finish() const;
  const std::string& file() const { return file_; }
  [[noreturn]] void fail(const std::string& why) const;

private:
  void raw(void* p, std::size_t n);
  std::string data_;
  std::string file_;
  std::size_t pos_ = 0;
  std::string section_ = "(start)";
};

/// Write a checkpoint atomically: temporary file beside `path`, fsync, rename, fsync of the folder.
void write_checkpoint(const std::filesystem::path& path, const CheckpointFingerprint& fingerprint,
                      const CheckpointWriter& payload);

/// Read and check a checkpoint: magic, version, byte order, size and checksum, then the
/// fingerprint against `expected`. Returns a reader positioned at the start of the payload.
/// Throws CheckpointError with a one-line reason otherwise.
CheckpointReader read_checkpoint(const std::filesystem::path& path,
                                 const CheckpointFingerprint& expected);

/// Only the fingerprint of a checkpoint (after the integrity checks), e.g. to print it.
CheckpointFingerprint read_checkpoint_fingerprint(const std::filesystem::path& path);

/// A double as the shortest text that reads back to the same bits, so fingerprints compare bit
/// patterns and stay readable in messages.
std::string exact_text(double v);

} // namespace pd
