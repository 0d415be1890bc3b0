#include "libpd/core/binary_state.hpp"

#include <fmt/format.h>

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

void CheckpointReader::fail(const std::string& why) const {
  throw CheckpointError(fmt::format("checkpoint {}: section '{}': {}", file_, section_, why));
}

void CheckpointReader::raw(void* p, std::size_t n) {
  if (n > data_.size() - pos_) {
    fail("ends early (the file does not match this version of pd)");
  }
  std::memcpy(p, data_.data() + pos_, n);
  pos_ += n;
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

std::string CheckpointReader::string() {
  const std::uint64_t n = u64();
  if (n > data_.size() - pos_) {
    fail("a string runs past the end");
  }
  std::string s = data_.substr(pos_, n);
  pos_ += n;
  return s;
}

std::vector<double> CheckpointReader::doubles() {
  const std::uint64_t n = u64();
  if (n > (data_.size() - pos_) / sizeof(double)) {
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
  if (n > data_.size() - pos_) {
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
  if (pos_ != data_.size()) {
    fail(fmt::format("{} unread bytes at the end", data_.size() - pos_));
  }
}

} // namespace pd
