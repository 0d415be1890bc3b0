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

/// 2: per-particle and per-bond values keyed by global index (KEYS), so a set written on any
/// number of ranks restarts on any other.
inline constexpr std::uint32_t checkpoint_format_version = 2;

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

/// Where one process's per-particle and per-bond values live in the whole model, so that a
/// checkpoint written on N ranks restarts on M (the values are keyed by global particle index,
/// bonds by their place in their particle's row, which is the whole model's row: a global bond
/// index). `global` and `owned` per local particle (empty: the identity, all owned); `rows` the
/// local bond rows' CSR offsets (a row is empty where the process computes no forces).
struct CheckpointLayout {
  std::size_t particles = 0;
  std::vector<std::uint32_t> global;
  std::vector<std::uint8_t> owned;
  std::vector<std::size_t> rows;

  std::uint32_t global_of(std::size_t i) const {
    return global.empty() ? static_cast<std::uint32_t>(i) : global[i];
  }
  bool owns(std::size_t i) const { return owned.empty() || owned[i] != 0; }
  std::size_t row_length(std::size_t i) const { return rows.empty() ? 0 : rows[i + 1] - rows[i]; }
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
  /// The KEYS section: which piece of how many this is, and the global keys of the particles
  /// this piece owns with their bond-row lengths. Comes before any per_particle or per_bond.
  void keys(const CheckpointLayout& layout, std::uint64_t piece, std::uint64_t pieces);
  /// Values of the owned particles only (each owner writes its own; halo copies are read back
  /// from their owners). `v` is empty or holds blocks of `width` values per local particle.
  void per_particle(const std::vector<double>& v, std::size_t width);
  /// Values of the owned particles' bond rows (`v` empty or one value per local bond).
  void per_bond(const std::vector<double>& v);
  void per_bond(const std::vector<std::uint8_t>& v);
  const std::string& data() const { return data_; }

private:
  void raw(const void* p, std::size_t n) { data_.append(static_cast<const char*>(p), n); }
  template <class T>
  void owned_rows(const std::vector<T>& v);
  std::string data_;
  CheckpointLayout layout_;
  bool keyed_ = false;
};

/// Reads what CheckpointWriter wrote, in the same order. Every read is bounds-checked; a mismatch
/// throws CheckpointError naming the file and the section.
///
/// A reader may hold the pieces of a set (one per rank that wrote it): everything but the keyed
/// values must then be the same in every piece (the run's scalars, step and history), and
/// per_particle/per_bond assemble this process's values from the pieces that own them.
class CheckpointReader {
public:
  struct Piece {
    std::string data;
    std::string file;
    std::size_t pos = 0;
  };
  CheckpointReader(std::string data, std::string file);
  explicit CheckpointReader(std::vector<Piece> pieces);
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
  /// Reads every piece's KEYS and finds, for each particle of `target` (owned or halo), the one
  /// piece that owns it; a particle owned by no piece or by two is refused, naming the files.
  void keys(const CheckpointLayout& target);
  /// This process's values, `size` of them (0: the array is absent; else blocks of `width` per
  /// local particle, or one per local bond).
  std::vector<double> per_particle(std::size_t size, std::size_t width, std::string_view what);
  std::vector<double> per_bond(std::size_t size, std::string_view what);
  std::vector<std::uint8_t> per_bond_bytes(std::size_t size, std::string_view what);
  /// The number of pieces the set was written in (1 before keys() is read).
  std::size_t pieces() const { return pieces_.size(); }
  /// Throws unless every byte has been read.
  void finish() const;
  const std::string& file() const { return pieces_.front().file; }
  [[noreturn]] void fail(const std::string& why) const;

private:
  /// Where a local particle's values are: piece, place among that piece's owned particles.
  struct Source {
    std::uint32_t piece = 0;
    std::uint32_t index = 0;
  };
  void raw(void* p, std::size_t n);
  std::size_t left() const; ///< bytes not yet read (of the first piece; all read alike)
  void raw_from(Piece& piece, void* p, std::size_t n);
  std::uint64_t u64_from(Piece& piece);
  template <class T>
  std::vector<T> keyed(std::size_t size, std::size_t width, bool bonds, std::string_view what);
  std::vector<Piece> pieces_;
  std::string section_ = "(start)";
  CheckpointLayout target_;
  std::vector<Source> source_;                       ///< per local particle of the target
  std::vector<std::vector<std::size_t>> piece_rows_; ///< per piece: CSR of its owned rows
  std::vector<std::size_t> piece_owned_;             ///< per piece: particles it owns
  bool keyed_ = false;
};

} // namespace pd
