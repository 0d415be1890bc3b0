// Output: JSON text (checked by parsing it back), atomic file replacement and VTU files.
#include "libpd/io/output.hpp"
#include "libpd/kernel/stable_time_step.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <unistd.h>
#include <variant>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// A strict little JSON reader (RFC 8259 subset without surrogate pairs): enough to prove that
/// dump() writes valid JSON and to read the values back.
struct Value {
  enum class Type { null, boolean, number, string, array, object } type = Type::null;
  bool b = false;
  double n = 0;
  std::string s;
  std::vector<Value> a;
  std::vector<std::pair<std::string, Value>> o;

  const Value& at(const std::string& key) const {
    for (const auto& [k, v] : o) {
      if (k == key) {
        return v;
      }
    }
    throw std::runtime_error("missing key " + key);
  }
};

class Reader {
public:
  explicit Reader(std::string text) : t_(std::move(text)) {}

  Value document() {
    Value v = value();
    ws();
    if (p_ != t_.size()) {
      fail("trailing characters");
    }
    return v;
  }

private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(what + " at offset " + std::to_string(p_));
  }
  void ws() {
    while (p_ < t_.size() &&
           (t_[p_] == ' ' || t_[p_] == '\n' || t_[p_] == '\t' || t_[p_] == '\r')) {
      ++p_;
    }
  }
  bool eat(const std::string& word) {
    if (t_.compare(p_, word.size(), word) == 0) {
      p_ += word.size();
      return true;
    }
    return false;
  }
  char next() {
    if (p_ >= t_.size()) {
      fail("unexpected end");
    }
    return t_[p_++];
  }
  std::string string() {
    if (next() != '"') {
      fail("expected string");
    }
    std::string out;
    for (;;) {
      const char c = next();
      if (c == '"') {
        return out;
      }
      if (static_cast<unsigned char>(c) < 0x20) {
        fail("raw control character in string");
      }
      if (c != '\\') {
        out += c;
        continue;
      }
      const char e = next();
      switch (e) {
      case '"':
      case '\\':
      case '/':
        out += e;
        break;
      case 'n':
        out += '\n';
        break;
      case 't':
        out += '\t';
        break;
      case 'r':
        out += '\r';
        break;
      case 'b':
        out += '\b';
        break;
      case 'f':
        out += '\f';
        break;
      case 'u': {
        const std::string hex = t_.substr(p_, 4);
        p_ += 4;
        const long code = std::stol(hex, nullptr, 16);
        if (code >= 0x80) {
          fail("non-ASCII \\u escape not supported by this reader");
        }
        out += static_cast<char>(code);
        break;
      }
      default:
        fail("bad escape");
      }
    }
  }
  Value value() {
    ws();
    Value v;
    if (p_ >= t_.size()) {
      fail("unexpected end");
    }
    const char c = t_[p_];
    if (eat("null")) {
      v.type = Value::Type::null;
    } else if (eat("true")) {
      v.type = Value::Type::boolean;
      v.b = true;
    } else if (eat("false")) {
      v.type = Value::Type::boolean;
    } else if (c == '"') {
      v.type = Value::Type::string;
      v.s = string();
    } else if (c == '[') {
      ++p_;
      v.type = Value::Type::array;
      ws();
      if (!eat("]")) {
        for (;;) {
          v.a.push_back(value());
          ws();
          if (eat("]")) {
            break;
          }
          if (!eat(",")) {
            fail("expected , or ]");
          }
        }
      }
    } else if (c == '{') {
      ++p_;
      v.type = Value::Type::object;
      ws();
      if (!eat("}")) {
        for (;;) {
          ws();
          std::string key = string();
          ws();
          if (!eat(":")) {
            fail("expected :");
          }
          v.o.emplace_back(std::move(key), value());
          ws();
          if (eat("}")) {
            break;
          }
          if (!eat(",")) {
            fail("expected , or }");
          }
        }
      }
    } else {
      // JSON number grammar: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
      const std::size_t start = p_;
      auto digits = [&] {
        const std::size_t d0 = p_;
        while (p_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[p_]))) {
          ++p_;
        }
        if (p_ == d0) {
          fail("expected digits");
        }
      };
      eat("-");
      if (!eat("0")) {
        digits();
      }
      if (eat(".")) {
        digits();
      }
      if (p_ < t_.size() && (t_[p_] == 'e' || t_[p_] == 'E')) {
        ++p_;
        if (!eat("+")) {
          eat("-");
        }
        digits();
      }
      v.type = Value::Type::number;
      v.n = std::stod(t_.substr(start, p_ - start));
    }
    return v;
  }

  std::string t_;
  std::size_t p_ = 0;
};

Value parse(const std::string& text) {
  return Reader(text).document();
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) {
    ++n;
  }
  return n;
}

TEST(Json, NestedDocumentRoundTrips) {
  pd::Json doc;
  doc["title"] = "beam \"A\"\nline two\twith tab and back\\slash";
  doc["count"] = 5229;
  doc["big"] = std::size_t{1} << 40;
  doc["negative"] = -17;
  doc["ratio"] = 0.1 + 0.2;
  doc["tiny"] = 1.25e-300;
  doc["flag"] = true;
  doc["off"] = false;
  doc["nothing"] = nullptr;
  doc["control"] = std::string("bell\x07") + "\x1f";
  doc["numbers"] = pd::Json::array_of(std::vector<double>{1.5, -2.0, 3e10});
  pd::Json rows = pd::Json::array();
  for (int i = 0; i < 3; ++i) {
    pd::Json row;
    row["i"] = i;
    row["list"] = pd::Json::array_of(std::vector<int>{i, i + 1});
    rows.push_back(row);
  }
  doc["rows"] = rows;
  doc["nested"]["deeper"]["deepest"] = "x";
  doc["empty_array"] = pd::Json::array();
  doc["empty_object"] = pd::Json::object();

  for (int indent : {2, 0, 4}) {
    SCOPED_TRACE(indent);
    const std::string text = doc.dump(indent);
    Value v;
    ASSERT_NO_THROW(v = parse(text)) << text;
    ASSERT_EQ(v.type, Value::Type::object);
    // Keys keep their insertion order.
    ASSERT_EQ(v.o.size(), 15u);
    EXPECT_EQ(v.o[0].first, "title");
    EXPECT_EQ(v.o[14].first, "empty_object");
    EXPECT_EQ(v.at("title").s, "beam \"A\"\nline two\twith tab and back\\slash");
    EXPECT_EQ(v.at("count").n, 5229);
    EXPECT_EQ(v.at("big").n, 1099511627776.0);
    EXPECT_EQ(v.at("negative").n, -17);
    EXPECT_EQ(v.at("ratio").n, 0.1 + 0.2); // shortest round-trip representation
    EXPECT_EQ(v.at("tiny").n, 1.25e-300);
    EXPECT_TRUE(v.at("flag").b);
    EXPECT_EQ(v.at("off").type, Value::Type::boolean);
    EXPECT_FALSE(v.at("off").b);
    EXPECT_EQ(v.at("nothing").type, Value::Type::null);
    EXPECT_EQ(v.at("control").s, std::string("bell\x07") + "\x1f");
    ASSERT_EQ(v.at("numbers").a.size(), 3u);
    EXPECT_EQ(v.at("numbers").a[2].n, 3e10);
    ASSERT_EQ(v.at("rows").a.size(), 3u);
    EXPECT_EQ(v.at("rows").a[2].at("list").a[1].n, 3);
    EXPECT_EQ(v.at("nested").at("deeper").at("deepest").s, "x");
    EXPECT_EQ(v.at("empty_array").type, Value::Type::array);
    EXPECT_TRUE(v.at("empty_array").a.empty());
    EXPECT_EQ(v.at("empty_object").type, Value::Type::object);
    EXPECT_TRUE(v.at("empty_object").o.empty());
  }
  // The escapes themselves, in the text.
  const std::string text = doc.dump();
  EXPECT_NE(text.find(R"(beam \"A\"\nline two\twith tab and back\\slash)"), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
}

TEST(Json, NonFiniteNumbersBecomeNull) {
  pd::Json doc;
  doc["nan"] = std::numeric_limits<double>::quiet_NaN();
  doc["inf"] = std::numeric_limits<double>::infinity();
  doc["minus_inf"] = -std::numeric_limits<double>::infinity();
  doc["mixed"] = pd::Json::array_of(
      std::vector<double>{1.0, std::nan(""), -std::numeric_limits<double>::infinity(), 2.0});
  const std::string text = doc.dump();
  // Only the keys spell these words; no value does.
  EXPECT_EQ(count(text, "nan"), 1u);
  EXPECT_EQ(count(text, "inf"), 2u);
  EXPECT_EQ(text.find("NaN"), std::string::npos);
  EXPECT_EQ(text.find("Infinity"), std::string::npos);
  const Value v = parse(text);
  EXPECT_EQ(v.at("nan").type, Value::Type::null);
  EXPECT_EQ(v.at("inf").type, Value::Type::null);
  EXPECT_EQ(v.at("minus_inf").type, Value::Type::null);
  ASSERT_EQ(v.at("mixed").a.size(), 4u);
  EXPECT_EQ(v.at("mixed").a[0].n, 1.0);
  EXPECT_EQ(v.at("mixed").a[1].type, Value::Type::null);
  EXPECT_EQ(v.at("mixed").a[2].type, Value::Type::null);
  EXPECT_EQ(v.at("mixed").a[3].n, 2.0);
}

TEST(Json, IntegersKeepTheirValue) {
  pd::Json doc;
  doc["max_int64"] = std::numeric_limits<long long>::max();
  doc["min_int64"] = std::numeric_limits<long long>::min();
  doc["two_pow_63"] = std::uint64_t{1} << 63; // e.g. a byte count or a hash
  doc["max_uint64"] = std::numeric_limits<unsigned long long>::max();
  const std::string text = doc.dump();
  EXPECT_NE(text.find("9223372036854775807"), std::string::npos);
  EXPECT_NE(text.find("-9223372036854775808"), std::string::npos);
  const Value v = parse(text);
  // An unsigned value must never come out negative.
  EXPECT_GT(v.at("two_pow_63").n, 0.0) << text;
  EXPECT_NEAR(v.at("two_pow_63").n, 9223372036854775808.0, 1e4);
  EXPECT_GT(v.at("max_uint64").n, 0.0) << text;
  EXPECT_NEAR(v.at("max_uint64").n, 18446744073709551615.0, 1e5);
}

TEST(Json, AccessorsAndMutation) {
  pd::Json doc;
  EXPECT_FALSE(doc.is_object());
  doc["a"] = 1;
  doc["a"] = 2.5; // replaces, keeps one key
  EXPECT_TRUE(doc.is_object());
  ASSERT_NE(doc.find("a"), nullptr);
  EXPECT_EQ(doc.find("a")->number(), 2.5);
  EXPECT_EQ(doc.find("b"), nullptr);
  doc["flag"] = true;
  EXPECT_EQ(doc.find("flag")->boolean(), true);
  EXPECT_FALSE(doc.find("flag")->number().has_value());
  doc["s"] = "text";
  EXPECT_FALSE(doc.find("s")->number().has_value());
  EXPECT_FALSE(doc.find("s")->boolean().has_value());
  doc["n"] = 7;
  EXPECT_EQ(doc.find("n")->number(), 7.0);
  const Value v = parse(doc.dump());
  EXPECT_EQ(v.o.size(), 4u);
  pd::Json list;
  list.push_back(1);
  list.push_back("two");
  const Value l = parse(list.dump());
  ASSERT_EQ(l.type, Value::Type::array);
  EXPECT_EQ(l.a[1].s, "two");
}

/// A fresh folder under the system temp dir, removed at the end of the test.
class TempDir {
public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("libpd_output_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

private:
  fs::path path_;
};

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    names.push_back(fs::relative(e.path(), dir).string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(WriteFileAtomically, CreatesReplacesAndLeavesNoTemporary) {
  TempDir tmp;
  const fs::path file = tmp.path() / "sub" / "dir" / "summary.json";
  const std::string long_text(100000, 'x');
  pd::write_file_atomically(file, long_text + "first");
  EXPECT_EQ(read(file), long_text + "first");
  EXPECT_EQ(listing(tmp.path()),
            (std::vector<std::string>{"sub", "sub/dir", "sub/dir/summary.json"}));
  // Shorter content replaces the file completely (no stale tail).
  pd::write_file_atomically(file, "second");
  EXPECT_EQ(read(file), "second");
  pd::write_file_atomically(file, "");
  EXPECT_EQ(read(file), "");
  EXPECT_EQ(listing(tmp.path()),
            (std::vector<std::string>{"sub", "sub/dir", "sub/dir/summary.json"}));
  // Binary content survives unchanged.
  const std::string binary("a\0b\r\n\xff", 6);
  pd::write_file_atomically(file, binary);
  EXPECT_EQ(read(file), binary);
}

TEST(WriteFileAtomically, FailedReplaceLeavesTargetAndNoTemporary) {
  TempDir tmp;
  // A non-empty directory in place of the target: the final rename fails. The target must be
  // untouched and the temporary cleaned up (repeated failures must not litter the output folder).
  const fs::path blocked = tmp.path() / "blocked";
  fs::create_directories(blocked / "child");
  EXPECT_ANY_THROW(pd::write_file_atomically(blocked, "new"));
  EXPECT_TRUE(fs::is_directory(blocked / "child"));
  EXPECT_EQ(listing(tmp.path()), (std::vector<std::string>{"blocked", "blocked/child"}));
}

/// A small 2D model, with damage so that the VTU also carries the damage array.
pd::Model small_model(bool damage = true) {
  pd::ModelSpec s;
  s.surface_correction = pd::SurfaceCorrection::none; // the bare model
  s.volume_correction = pd::VolumeCorrection::none;
  s.dimension.dim = 2;
  s.dimension.thickness = 0.01;
  s.lattice.spacing = 0.01;
  s.lattice.horizon_factor = 3.015;
  s.effects.damage = damage;
  pd::Material mat;
  mat.youngs_modulus = 1e9;
  mat.density = 1000;
  mat.critical_stretch = 1e-3;
  s.materials = {mat};
  pd::BodySpec b;
  b.region.boxes = {pd::Box{{0, 0, 0}, {0.1, 0.05, 0}}};
  s.bodies = {b};
  return pd::build_model(s);
}

TEST(WriteVtu, WritesParticlesAndFields) {
  TempDir tmp;
  pd::Model model = small_model();
  ASSERT_EQ(model.size(), 50u);
  pd::SolverSpec solver;
  solver.max_steps = 20;
  pd::InitialSpec initial;
  initial.displacement_gradient[0][0] = 1e-4;
  initial.velocity = {0.25, -0.5, 0};
  pd::Simulation sim(model, solver, initial);
  sim.run();
  const fs::path file = tmp.path() / "frames" / "final.vtu";
  pd::write_vtu(file, sim);
  const std::string text = read(file);
  EXPECT_NE(text.find("<VTKFile"), std::string::npos);
  EXPECT_NE(text.find("NumberOfPoints=\"50\""), std::string::npos);
  EXPECT_NE(text.find("</VTKFile>"), std::string::npos);
  for (const char* name :
       {"Name=\"displacement\"", "Name=\"velocity\"", "Name=\"damage\"", "Name=\"material\""}) {
    EXPECT_EQ(count(text, name), 1u) << name;
  }
  // Displacements of particle 0 as written, read back.
  const std::size_t start = text.find('\n', text.find("Name=\"displacement\"")) + 1;
  std::istringstream row(text.substr(start, text.find('\n', start) - start));
  double u[3];
  row >> u[0] >> u[1] >> u[2];
  EXPECT_DOUBLE_EQ(u[0], sim.displacement(0, 0));
  EXPECT_DOUBLE_EQ(u[1], sim.displacement(0, 1));
  EXPECT_EQ(listing(tmp.path()), (std::vector<std::string>{"frames", "frames/final.vtu"}));
}

TEST(WriteVtu, RefusesNonFiniteDisplacements) {
  TempDir tmp;
  const fs::path file = tmp.path() / "state.vtu";
  {
    // A valid file first: a refused write must leave it as it was.
    pd::Model model = small_model();
    pd::Simulation sim(model, pd::SolverSpec{});
    pd::write_vtu(file, sim);
  }
  const std::string before = read(file);
  ASSERT_NE(before.find("<VTKFile"), std::string::npos);

  // A run with far too large a step and no blow-up limit goes to inf and NaN (without damage:
  // broken bonds would stop the growth).
  pd::Model model = small_model(false);
  pd::SolverSpec solver;
  solver.dt = 5 * pd::stable_time_step(model);
  solver.blowup_displacement = std::numeric_limits<double>::max();
  solver.max_steps = 100'000;
  pd::InitialSpec initial;
  initial.displacement_gradient[0][0] = 1e-6;
  pd::Simulation sim(model, solver, initial);
  auto any_nonfinite = [&] {
    for (std::size_t i = 0; i < model.size(); ++i) {
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(sim.displacement(i, c))) {
          return true;
        }
      }
    }
    return false;
  };
  // The run stops once |u|² overflows, while u itself may still be finite; continuing the run a
  // few more steps reaches inf/NaN in u.
  for (int attempt = 0; attempt < 100 && !any_nonfinite(); ++attempt) {
    const pd::RunResult r = sim.run();
    ASSERT_EQ(r.status, pd::RunStatus::unstable);
  }
  ASSERT_TRUE(any_nonfinite());
  EXPECT_THROW(pd::write_vtu(file, sim), std::runtime_error);
  EXPECT_EQ(read(file), before);
  EXPECT_EQ(listing(tmp.path()), (std::vector<std::string>{"state.vtu"}));

  // A single NaN displacement from the start is refused too.
  pd::Model model2 = small_model();
  pd::InitialSpec bad;
  bad.displacement_gradient[1][1] = std::numeric_limits<double>::quiet_NaN();
  pd::Simulation sim2(model2, pd::SolverSpec{}, bad);
  EXPECT_THROW(pd::write_vtu(tmp.path() / "bad.vtu", sim2), std::runtime_error);
  EXPECT_FALSE(fs::exists(tmp.path() / "bad.vtu"));
}

} // namespace
