#include "libpd/core/binary_state.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <limits>

namespace pd {

// --- CheckpointWriter / CheckpointReader -------------------------------------------------------

void CheckpointWriter::section(std::string_view tag) {
  std::string t(tag);
  t.resize(4, ' ');
  data_ += t;
}

void CheckpointWriter::string(std::string_view s) {
  u64(s.size());
  data_.append(s);
}

void CheckpointWriter::doubles(const std::vector<double>& v) {
  u64(v.size());
  if (!v.empty()) {
    raw(v.data(), v.size() * sizeof(double));
  }
}

void CheckpointWriter::bytes(const std::vector<std::uint8_t>& v) {
  u64(v.size());
  if (!v.empty()) {
    raw(v.data(), v.size());
  }
}

void CheckpointWriter::keys(const CheckpointLayout& layout, std::uint64_t piece,
                            std::uint64_t pieces) {
  layout_ = layout;
  keyed_ = true;
  section("KEYS");
  u64(piece);
  u64(pieces);
  std::vector<std::uint32_t> global;
  std::vector<std::uint64_t> lengths;
  for (std::size_t i = 0; i < layout.particles; ++i) {
    if (layout.owns(i)) {
      global.push_back(layout.global_of(i));
      lengths.push_back(layout.row_length(i));
    }
  }
  u64(global.size());
  if (!global.empty()) {
    raw(global.data(), global.size() * sizeof(std::uint32_t));
    raw(lengths.data(), lengths.size() * sizeof(std::uint64_t));
  }
}

void CheckpointWriter::per_particle(const std::vector<double>& v, std::size_t width) {
  if (!keyed_) {
    throw std::logic_error("CheckpointWriter::per_particle before keys");
  }
  const std::size_t n = layout_.particles;
  const std::size_t blocks = n * width == 0 ? 0 : v.size() / (n * width);
  if (blocks * n * width != v.size()) {
    throw std::logic_error("CheckpointWriter::per_particle: size is not blocks × particles");
  }
  std::vector<double> out;
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::size_t i = 0; i < n; ++i) {
      if (layout_.owns(i)) {
        const auto at = v.begin() + static_cast<std::ptrdiff_t>((b * n + i) * width);
        out.insert(out.end(), at, at + static_cast<std::ptrdiff_t>(width));
      }
    }
  }
  doubles(out);
}

template <class T>
void CheckpointWriter::owned_rows(const std::vector<T>& v) {
  if (!keyed_) {
    throw std::logic_error("CheckpointWriter::per_bond before keys");
  }
  std::vector<T> out;
  if (!v.empty()) {
    if (layout_.rows.empty() || v.size() != layout_.rows.back()) {
      throw std::logic_error("CheckpointWriter::per_bond: not one value per local bond");
    }
    for (std::size_t i = 0; i < layout_.particles; ++i) {
      if (layout_.owns(i)) {
        out.insert(out.end(), v.begin() + static_cast<std::ptrdiff_t>(layout_.rows[i]),
                   v.begin() + static_cast<std::ptrdiff_t>(layout_.rows[i + 1]));
      }
    }
  }
  u64(out.size());
  if (!out.empty()) {
    raw(out.data(), out.size() * sizeof(T));
  }
}

void CheckpointWriter::per_bond(const std::vector<double>& v) {
  owned_rows(v);
}

void CheckpointWriter::per_bond(const std::vector<std::uint8_t>& v) {
  owned_rows(v);
}

CheckpointReader::CheckpointReader(std::string data, std::string file) {
  pieces_.push_back({std::move(data), std::move(file), 0});
}

CheckpointReader::CheckpointReader(std::vector<Piece> pieces) : pieces_(std::move(pieces)) {
  if (pieces_.empty()) {
    throw CheckpointError("a checkpoint set of no pieces");
  }
}

void CheckpointReader::fail(const std::string& why) const {
  throw CheckpointError(fmt::format("checkpoint {}: section '{}': {}", file(), section_, why));
}

void CheckpointReader::raw_from(Piece& piece, void* p, std::size_t n) {
  if (n > piece.data.size() - piece.pos) {
    throw CheckpointError(
        fmt::format("checkpoint {}: section '{}': ends early (the file does not match this "
                    "version of pd)",
                    piece.file, section_));
  }
  std::memcpy(p, piece.data.data() + piece.pos, n);
  piece.pos += n;
}

std::uint64_t CheckpointReader::u64_from(Piece& piece) {
  std::uint64_t v = 0;
  raw_from(piece, &v, sizeof v);
  return v;
}

// Everything outside the keyed values is the same in every piece of a set written at one step;
// a difference means pieces of different steps (a set mixed by a run stopped while writing it).
void CheckpointReader::raw(void* p, std::size_t n) {
  raw_from(pieces_.front(), p, n);
  std::string other(n, '\0');
  for (std::size_t k = 1; k < pieces_.size(); ++k) {
    raw_from(pieces_[k], other.data(), n);
    if (n > 0 && std::memcmp(other.data(), p, n) != 0) {
      throw CheckpointError(fmt::format(
          "checkpoint pieces {} and {} differ in section '{}' (they are of different steps: the "
          "run was stopped while writing them); restart from an earlier set",
          pieces_.front().file, pieces_[k].file, section_));
    }
  }
}

void CheckpointReader::keys(const CheckpointLayout& target) {
  section("KEYS");
  const std::size_t count = pieces_.size();
  std::vector<std::size_t> by_rank(count, count);
  std::vector<std::vector<std::uint32_t>> owned(count);
  piece_rows_.assign(count, {});
  piece_owned_.assign(count, 0);
  std::uint32_t largest = 0;
  for (std::size_t k = 0; k < count; ++k) {
    Piece& piece = pieces_[k];
    const std::uint64_t rank = u64_from(piece);
    const std::uint64_t ranks = u64_from(piece);
    if (ranks != count || rank >= count || by_rank[rank] != count) {
      throw CheckpointError(fmt::format("checkpoint {}: piece {} of {}, but the set read has {} "
                                        "pieces{}",
                                        piece.file, rank, ranks, count,
                                        rank < count && by_rank[rank] != count ? " (twice)" : ""));
    }
    by_rank[rank] = k;
    const std::uint64_t n = u64_from(piece);
    if (n > (piece.data.size() - piece.pos) / (sizeof(std::uint32_t) + sizeof(std::uint64_t))) {
      throw CheckpointError(
          fmt::format("checkpoint {}: section 'KEYS' runs past the end", piece.file));
    }
    owned[k].resize(n);
    std::vector<std::uint64_t> lengths(n);
    if (n > 0) {
      raw_from(piece, owned[k].data(), n * sizeof(std::uint32_t));
      raw_from(piece, lengths.data(), n * sizeof(std::uint64_t));
      largest = std::max(largest, *std::max_element(owned[k].begin(), owned[k].end()));
    }
    piece_owned_[k] = n;
    std::vector<std::size_t>& rows = piece_rows_[k];
    rows.assign(1, 0);
    for (const std::uint64_t l : lengths) {
      rows.push_back(rows.back() + l);
    }
  }
  for (std::size_t i = 0; i < target.particles; ++i) {
    largest = std::max(largest, target.global_of(i));
  }
  constexpr std::uint32_t nowhere = std::numeric_limits<std::uint32_t>::max();
  std::vector<Source> where(std::size_t{largest} + 1, Source{nowhere, 0});
  for (std::size_t k = 0; k < count; ++k) {
    for (std::size_t j = 0; j < owned[k].size(); ++j) {
      Source& s = where[owned[k][j]];
      if (s.piece != nowhere) {
        throw CheckpointError(
            fmt::format("checkpoint pieces {} and {} both hold particle {}: they are not one set",
                        pieces_[s.piece].file, pieces_[k].file, owned[k][j]));
      }
      s = {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(j)};
    }
  }
  source_.resize(target.particles);
  std::vector<std::uint32_t> missing;
  for (std::size_t i = 0; i < target.particles; ++i) {
    source_[i] = where[target.global_of(i)];
    if (source_[i].piece == nowhere) {
      missing.push_back(target.global_of(i));
      continue;
    }
    const Source s = source_[i];
    const std::size_t length = piece_rows_[s.piece][s.index + 1] - piece_rows_[s.piece][s.index];
    if (target.row_length(i) != 0 && target.row_length(i) != length) {
      throw CheckpointError(fmt::format("checkpoint {}: particle {} has {} bonds there, {} in this "
                                        "run",
                                        pieces_[s.piece].file, target.global_of(i), length,
                                        target.row_length(i)));
    }
  }
  if (!missing.empty()) {
    std::sort(missing.begin(), missing.end());
    std::string files;
    for (const Piece& p : pieces_) {
      files += (files.empty() ? "" : ", ") + p.file;
    }
    throw CheckpointError(fmt::format(
        "checkpoint set {}: {} particle(s) this run needs are in no piece (global indices {} to "
        "{}); the set is incomplete or of another model",
        files, missing.size(), missing.front(), missing.back()));
  }
  target_ = target;
  keyed_ = true;
}

template <class T>
std::vector<T> CheckpointReader::keyed(std::size_t size, std::size_t width, bool bonds,
                                       std::string_view what) {
  if (!keyed_) {
    throw std::logic_error("CheckpointReader: keyed values before keys");
  }
  const std::size_t n = target_.particles;
  const std::size_t target_bonds = target_.rows.empty() ? 0 : target_.rows.back();
  const std::size_t per_block = bonds ? target_bonds : n * width;
  const std::size_t blocks = size == 0 || per_block == 0 ? 0 : size / per_block;
  if (blocks * per_block != size) {
    fail(fmt::format("{}: {} values are not whole blocks of {}", what, size, per_block));
  }
  std::vector<std::vector<T>> from(pieces_.size());
  for (std::size_t k = 0; k < pieces_.size(); ++k) {
    Piece& piece = pieces_[k];
    const std::uint64_t count = u64_from(piece);
    const std::size_t expected = blocks * (bonds ? piece_rows_[k].back() : piece_owned_[k] * width);
    if (count != expected) {
      throw CheckpointError(fmt::format("checkpoint {}: section '{}': {} has {} values, this run "
                                        "needs {}",
                                        piece.file, section_, what, count, expected));
    }
    from[k].resize(count);
    if (count > 0) {
      raw_from(piece, from[k].data(), count * sizeof(T));
    }
  }
  std::vector<T> out(size);
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::size_t i = 0; i < n; ++i) {
      const Source s = source_[i];
      const std::vector<T>& v = from[s.piece];
      if (bonds) {
        const std::size_t length = target_.row_length(i);
        const std::size_t at = piece_rows_[s.piece][s.index];
        std::copy_n(v.begin() + static_cast<std::ptrdiff_t>(b * piece_rows_[s.piece].back() + at),
                    length,
                    out.begin() + static_cast<std::ptrdiff_t>(b * target_bonds + target_.rows[i]));
      } else {
        std::copy_n(v.begin() +
                        static_cast<std::ptrdiff_t>((b * piece_owned_[s.piece] + s.index) * width),
                    width, out.begin() + static_cast<std::ptrdiff_t>((b * n + i) * width));
      }
    }
  }
  return out;
}

std::vector<double> CheckpointReader::per_particle(std::size_t size, std::size_t width,
                                                   std::string_view what) {
  return keyed<double>(size, width, false, what);
}

std::vector<double> CheckpointReader::per_bond(std::size_t size, std::string_view what) {
  return keyed<double>(size, 1, true, what);
}

std::vector<std::uint8_t> CheckpointReader::per_bond_bytes(std::size_t size,
                                                           std::string_view what) {
  return keyed<std::uint8_t>(size, 1, true, what);
}

void CheckpointReader::section(std::string_view tag) {
  std::string t(tag);
  t.resize(4, ' ');
  std::string got(4, ' ');
  raw(got.data(), 4);
  if (got != t) {
    fail(fmt::format("expected section '{}', found '{}'", t, got));
  }
  section_ = t;
}

std::uint64_t CheckpointReader::u64() {
  std::uint64_t v = 0;
  raw(&v, sizeof v);
  return v;
}

double CheckpointReader::f64() {
  double v = 0;
  raw(&v, sizeof v);
  return v;
}

std::size_t CheckpointReader::left() const {
  const Piece& p = pieces_.front();
  return p.data.size() - p.pos;
}

std::string CheckpointReader::string() {
  const std::uint64_t n = u64();
  if (n > left()) {
    fail("a string runs past the end");
  }
  std::string s(n, '\0');
  raw(s.data(), n);
  return s;
}

std::vector<double> CheckpointReader::doubles() {
  const std::uint64_t n = u64();
  if (n > left() / sizeof(double)) {
    fail("an array runs past the end");
  }
  std::vector<double> v(n);
  if (n > 0) {
    raw(v.data(), n * sizeof(double));
  }
  return v;
}

std::vector<std::uint8_t> CheckpointReader::bytes() {
  const std::uint64_t n = u64();
  if (n > left()) {
    fail("an array runs past the end");
  }
  std::vector<std::uint8_t> v(n);
  if (n > 0) {
    raw(v.data(), n);
  }
  return v;
}

std::vector<double> CheckpointReader::doubles(std::size_t size, std::string_view what) {
  std::vector<double> v = doubles();
  if (v.size() != size) {
    fail(fmt::format("{} has {} values, this run needs {}", what, v.size(), size));
  }
  return v;
}

std::vector<std::uint8_t> CheckpointReader::bytes(std::size_t size, std::string_view what) {
  std::vector<std::uint8_t> v = bytes();
  if (v.size() != size) {
    fail(fmt::format("{} has {} values, this run needs {}", what, v.size(), size));
  }
  return v;
}

void CheckpointReader::finish() const {
  for (const Piece& p : pieces_) {
    if (p.pos != p.data.size()) {
      throw CheckpointError(fmt::format("checkpoint {}: section '{}': {} unread bytes at the end",
                                        p.file, section_, p.data.size() - p.pos));
    }
  }
}

} // namespace pd
