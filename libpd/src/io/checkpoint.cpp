#include "libpd/io/checkpoint.hpp"

#include "libpd/core/atomic_file.hpp"
#include "libpd/core/file_input.hpp"

#include <fmt/format.h>
#include <iterator>
#include <limits>

namespace pd {

namespace {

constexpr char magic[8] = {'L', 'I', 'B', 'P', 'D', 'C', 'K', 'P'};
constexpr std::uint32_t byte_order_marker = 0x01020304;
/// magic, version, marker, fingerprint length, payload length, checksum
constexpr std::size_t fixed_bytes = 8 + 4 + 4 + 8 + 8 + 8;

void append(std::string& s, const void* p, std::size_t n) {
  s.append(static_cast<const char*>(p), n);
}

void append_string(std::string& s, std::string_view v) {
  const std::uint64_t n = v.size();
  append(s, &n, sizeof n);
  s.append(v);
}

std::string encode_fingerprint(const CheckpointFingerprint& f) {
  std::string s;
  append_string(s, f.scene);
  const auto count = static_cast<std::uint32_t>(f.items.size());
  append(s, &count, sizeof count);
  for (const auto& [k, v] : f.items) {
    append_string(s, k);
    append_string(s, v);
  }
  return s;
}

[[noreturn]] void refuse(const std::filesystem::path& path, const std::string& why) {
  throw CheckpointError(fmt::format("checkpoint {}: {}", path.string(), why));
}

/// The parsed, integrity-checked parts of a file.
struct Parsed {
  CheckpointFingerprint fingerprint;
  std::string payload;
};

Parsed parse(const std::filesystem::path& path) {
  std::string s;
  try {
    s = read_regular_file(path, std::numeric_limits<std::size_t>::max());
  } catch (const FileInputError& e) {
    refuse(path, e.what());
  }
  if (s.size() < sizeof magic || std::memcmp(s.data(), magic, sizeof magic) != 0) {
    refuse(path, "is not a libpd checkpoint (wrong magic bytes)");
  }
  if (s.size() < fixed_bytes) {
    refuse(path, fmt::format("is truncated ({} bytes; even an empty checkpoint has {})", s.size(),
                             fixed_bytes));
  }
  std::size_t pos = sizeof magic;
  auto take = [&](void* p, std::size_t n) {
    std::memcpy(p, s.data() + pos, n);
    pos += n;
  };
  std::uint32_t version = 0, marker = 0;
  take(&version, sizeof version);
  take(&marker, sizeof marker);
  if (marker != byte_order_marker) {
    refuse(path, "was written on a machine of the other byte order (or is corrupt)");
  }
  if (version != checkpoint_format_version) {
    refuse(path, fmt::format("has format version {}; this pd reads version {}", version,
                             checkpoint_format_version));
  }
  std::uint64_t header_len = 0, payload_len = 0;
  take(&header_len, sizeof header_len);
  // Lengths are checked against the file size before use, so a damaged length cannot overflow.
  if (header_len > s.size() - fixed_bytes) {
    refuse(path, fmt::format("is truncated or corrupt: {} bytes, fingerprint alone claims {}",
                             s.size(), header_len));
  }
  const std::size_t header_at = pos;
  pos += header_len;
  take(&payload_len, sizeof payload_len);
  const std::size_t expected = fixed_bytes + header_len + payload_len;
  if (payload_len > s.size() || expected != s.size()) {
    refuse(path, fmt::format("is truncated or corrupt: {} bytes where its header says {}", s.size(),
                             expected));
  }
  const std::size_t payload_at = pos;
  pos += payload_len;
  std::uint64_t stored = 0;
  take(&stored, sizeof stored);
  Fnv1a h;
  h.add(s.data(), s.size() - sizeof stored);
  if (h.value() != stored) {
    refuse(path, fmt::format("is corrupt: checksum {:016x} does not match the stored {:016x}",
                             h.value(), stored));
  }

  Parsed out;
  const std::string& hs = s;
  std::size_t hp = header_at;
  const std::size_t hend = header_at + header_len;
  auto hread = [&](void* p, std::size_t n) {
    if (hp + n > hend) {
      refuse(path, "has a malformed fingerprint");
    }
    std::memcpy(p, hs.data() + hp, n);
    hp += n;
  };
  auto hstring = [&] {
    std::uint64_t n = 0;
    hread(&n, sizeof n);
    if (n > hend - hp) {
      refuse(path, "has a malformed fingerprint");
    }
    std::string v = hs.substr(hp, n);
    hp += n;
    return v;
  };
  out.fingerprint.scene = hstring();
  std::uint32_t count = 0;
  hread(&count, sizeof count);
  for (std::uint32_t k = 0; k < count; ++k) {
    std::string key = hstring();
    std::string value = hstring();
    out.fingerprint.add(std::move(key), std::move(value));
  }
  out.payload = s.substr(payload_at, payload_len);
  return out;
}

} // namespace

const std::string* CheckpointFingerprint::find(std::string_view key) const {
  for (const auto& [k, v] : items) {
    if (k == key) {
      return &v;
    }
  }
  return nullptr;
}

std::string exact_text(double v) {
  return fmt::format("{}", v); // shortest text that reads back to the same bits
}

// --- Files -------------------------------------------------------------------------------------

void write_checkpoint(const std::filesystem::path& path, const CheckpointFingerprint& fingerprint,
                      const CheckpointWriter& payload) {
  const std::string header = encode_fingerprint(fingerprint);
  std::string s;
  s.reserve(fixed_bytes + header.size() + payload.data().size());
  append(s, magic, sizeof magic);
  append(s, &checkpoint_format_version, sizeof checkpoint_format_version);
  append(s, &byte_order_marker, sizeof byte_order_marker);
  const std::uint64_t header_len = header.size();
  append(s, &header_len, sizeof header_len);
  s += header;
  const std::uint64_t payload_len = payload.data().size();
  append(s, &payload_len, sizeof payload_len);
  s += payload.data();
  Fnv1a h;
  h.add(s.data(), s.size());
  const std::uint64_t checksum = h.value();
  append(s, &checksum, sizeof checksum);

  try {
    write_file_atomically(path, s, Durability::synced);
  } catch (const std::runtime_error& e) {
    throw CheckpointError(e.what());
  }
}

bool is_checkpoint_file(const std::filesystem::path& path) {
  return regular_file_starts_with(path, std::string(magic, sizeof magic));
}

CheckpointFingerprint read_checkpoint_fingerprint(const std::filesystem::path& path) {
  return parse(path).fingerprint;
}

namespace {

Parsed parse_and_compare(const std::filesystem::path& path, const CheckpointFingerprint& expected) {
  Parsed p = parse(path);
  std::vector<std::string> differences;
  for (const auto& [key, value] : expected.items) {
    const std::string* theirs = p.fingerprint.find(key);
    if (theirs == nullptr) {
      differences.push_back(fmt::format("{} (missing in the checkpoint, this run {})", key, value));
    } else if (*theirs != value) {
      differences.push_back(fmt::format("{} (checkpoint {}, this run {})", key, *theirs, value));
    }
  }
  for (const auto& [key, value] : p.fingerprint.items) {
    if (expected.find(key) == nullptr) {
      differences.push_back(fmt::format("{} (checkpoint {}, unknown to this run)", key, value));
    }
  }
  if (!differences.empty()) {
    auto get = [&](const CheckpointFingerprint& f, std::string_view k) {
      const std::string* v = f.find(k);
      return v != nullptr ? *v : std::string("?");
    };
    std::string list;
    for (const auto& d : differences) {
      list += (list.empty() ? "" : "; ") + d;
    }
    refuse(path, fmt::format("was written for scene '{}' ({} particles, {} bonds, integrator {}); "
                             "this run (scene '{}': {} particles, {} bonds, integrator {}) "
                             "differs in: {}",
                             p.fingerprint.scene, get(p.fingerprint, "particles"),
                             get(p.fingerprint, "bonds"), get(p.fingerprint, "integrator"),
                             expected.scene, get(expected, "particles"), get(expected, "bonds"),
                             get(expected, "integrator"), list));
  }
  return p;
}

} // namespace

CheckpointReader read_checkpoint(const std::filesystem::path& path,
                                 const CheckpointFingerprint& expected) {
  Parsed p = parse_and_compare(path, expected);
  return CheckpointReader(std::move(p.payload), path.string());
}

CheckpointReader read_checkpoint_set(const std::vector<std::filesystem::path>& pieces,
                                     const CheckpointFingerprint& expected) {
  std::vector<CheckpointReader::Piece> read;
  for (const std::filesystem::path& path : pieces) {
    read.push_back({parse_and_compare(path, expected).payload, path.string(), 0});
  }
  return CheckpointReader(std::move(read));
}

} // namespace pd
