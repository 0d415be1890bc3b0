// The binary state of a run: a tagged, bounds-checked payload that the simulation and each
// integrator write their state into and read it back from, and the FNV-1a checksum used to detect
// damaged or unequal data. The file around it (fingerprint, atomic write, integrity checks) is
// io/checkpoint.hpp; this part sits low so that an integrator can save its state without knowing
// about files.
#pragma once

#include <cstdint>
#include <cstring>
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

} // namespace pd
