// Scene fuzzing: a deterministic mutator over the shipped scenes (verification/scenes/*.yaml).
//
// Every case mutates one scene (a deleted key, a scalar replaced by text, a list, a map, NaN,
// ±inf, −1, 0, 1e308, huge integers, duplicated keys or list items, a truncated file, flipped or
// inserted bytes, a spacing so fine that the scene asks for gigabytes, a huge horizon or box,
// deep nesting, alias bombs, a body made a graded set or a particle file, a crack, ...) and must
// end in one of
//   * a pd::SceneError whose message is "NAME:LINE:COL: error: ..." with a hint, or
//   * a valid parse, which is then built and run with a hard cap (at most 20 steps, a few thousand
//     particles; bigger models are only built, huge ones only estimated) and must either finish
//     with finite results or report itself unstable, or fail with a clean std::exception.
// Anything else (another exception type from the parser, a crash, a sanitizer report, a case
// running longer than the watchdog allows) fails the test. The cases run in-process so that
// AddressSanitizer and UBSan see them (the `asan` presets).
//
// Environment: PD_FUZZ_CASES (default 300), PD_FUZZ_SEED, PD_FUZZ_FIRST (first case index),
// PD_FUZZ_ONLY (run one case and print its text), PD_FUZZ_CASE_SECONDS (watchdog, default 120).
// PD_MEMORY_LIMIT defaults to 1G here so the guard refuses the same cases on every machine.
#include "libpd/app/run.hpp"
#include "libpd/core/text.hpp"
#include "libpd/io/resources.hpp"
#include "libpd/io/scene.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include <yaml-cpp/yaml.h>

namespace {

namespace fs = std::filesystem;

std::size_t env_size(const char* name, std::size_t fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? static_cast<std::size_t>(std::stoull(v)) : fallback;
}

struct ShippedScene {
  std::string name;
  std::string text;
};

const std::vector<ShippedScene>& shipped_scenes() {
  static const std::vector<ShippedScene> scenes = [] {
    std::vector<ShippedScene> out;
    std::vector<fs::directory_entry> entries(fs::directory_iterator(PD_SCENES_DIR), {});
    for (const auto& folder : fs::directory_iterator(PD_CASES_DIR)) {
      if (folder.is_directory()) { // a case folder: its scenes, not its case.yaml
        for (const auto& entry : fs::directory_iterator(folder.path())) {
          if (entry.path().filename() != "case.yaml") {
            entries.push_back(entry);
          }
        }
      }
    }
    for (const auto& entry : entries) {
      if (entry.path().extension() == ".yaml") {
        std::ifstream in(entry.path(), std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        out.push_back({entry.path().filename().string(), text.str()});
      }
    }
    std::sort(out.begin(), out.end(),
              [](const ShippedScene& a, const ShippedScene& b) { return a.name < b.name; });
    return out;
  }();
  return scenes;
}

// ---------------------------------------------------------------------------------------------
// Mutator
// ---------------------------------------------------------------------------------------------

class Mutator {
public:
  explicit Mutator(std::uint64_t seed) : rng_(seed) {}

  /// Apply one to three mutations; `log` names them.
  std::string mutate(std::string text, std::vector<std::string>& log) {
    const int count = pick(10) < 7 ? 1 : 2 + pick(2);
    for (int i = 0; i < count; ++i) {
      text = once(text, log);
    }
    return text;
  }

private:
  std::mt19937_64 rng_;

  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  template <class T>
  const T& choose(const std::vector<T>& v) {
    return v[static_cast<std::size_t>(pick(static_cast<int>(v.size())))];
  }

  /// Where a node sits: in a map under `key`, or in a sequence at `index`.
  struct Slot {
    YAML::Node parent;
    bool in_map = true;
    YAML::Node key;
    std::size_t index = 0;
    YAML::Node node;
    std::string path;
  };

  /// Stops at `slot_budget` slots: an alias bomb expands to 9^9 nodes when walked or emitted.
  static constexpr std::size_t slot_budget = 20000;

  static void collect(const YAML::Node& n, const std::string& path, std::vector<Slot>& out,
                      int depth = 0) {
    // Deeply nested mutants (3000 levels) would overflow the stack here; the scene's own
    // structure is at most six levels deep.
    if (out.size() >= slot_budget || depth > 12) {
      return;
    }
    if (n.IsMap()) {
      for (auto it = n.begin(); it != n.end(); ++it) {
        const std::string p = path + "." + (it->first.IsScalar() ? it->first.Scalar() : "?");
        out.push_back({n, true, it->first, 0, it->second, p});
        collect(it->second, p, out, depth + 1);
      }
    } else if (n.IsSequence()) {
      for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string p = fmt::format("{}[{}]", path, i);
        out.push_back({n, false, {}, i, n[i], p});
        collect(n[i], p, out, depth + 1);
      }
    }
  }

  static void assign(Slot& s, const YAML::Node& value) {
    if (s.in_map) {
      s.parent[s.key] = value;
    } else {
      s.parent[s.index] = value;
    }
  }

  YAML::Node weird_value(const YAML::Node& old) {
    static const std::vector<std::string> scalars{
        "",
        "abc",
        ".nan",
        ".inf",
        "-.inf",
        "nan",
        "-1",
        "0",
        "1",
        "-0",
        "1e308",
        "-1e308",
        "1e-308",
        "4.9e-324",
        "1e400",
        "-1e400",
        "99999999999999999999999",
        "-9223372036854775809",
        "9223372036854775807",
        "18446744073709551616",
        "4294967297",
        "65536",
        "1e12",
        "1e19",
        "0x10",
        "1_000",
        "true",
        "null",
        "~",
        "auto",
        "x",
        "z",
        "damage",
        "exact",
        "rk4",
        "0.5",
        "1e-12",
        "3.4e38",
        "2.2250738585072014e-308",
        // Issue 18: huge scalars are not echoed whole, bytes that are not text are escaped.
        std::string(100000, '9'),
        std::string(20000, 'x') + "\xff",
        "\xff\xfe not utf-8",
        "a\x01\x1b[2Jb",
        "caf\xc3\xa9",
    };
    switch (pick(6)) {
    case 0: {
      YAML::Node seq(YAML::NodeType::Sequence);
      const int n = pick(5);
      for (int i = 0; i < n; ++i) {
        seq.push_back(choose(scalars));
      }
      return seq;
    }
    case 1: {
      YAML::Node map(YAML::NodeType::Map);
      map[choose(scalars) + "k"] = choose(scalars);
      return map;
    }
    case 2:
      if (old.IsScalar()) {
        double v = 0;
        std::istringstream in(old.Scalar());
        if (in >> v) {
          // Jitter a number: scale by 10^±8, flip its sign, nudge it by an ulp-sized amount.
          const double factor = std::pow(10.0, uniform(-8, 8));
          const double w = pick(3) == 0 ? -v : pick(2) == 0 ? v * factor : v * (1 + 1e-15);
          return YAML::Node(fmt::format("{}", w));
        }
      }
      return YAML::Node(choose(scalars));
    case 3:
      return YAML::Node(YAML::NodeType::Null);
    default:
      return YAML::Node(choose(scalars));
    }
  }

  std::string emit(const YAML::Node& root) {
    YAML::Emitter out;
    out << root;
    return out.c_str();
  }

  std::string once(const std::string& text, std::vector<std::string>& log) {
    const int op = pick(17);
    if (op < 9) {
      YAML::Node root;
      try {
        root = YAML::Load(text);
      } catch (const YAML::Exception&) {
        return bytes_op(text, log); // an earlier mutation broke the YAML: mutate bytes instead
      }
      std::vector<Slot> slots;
      collect(root, "", slots);
      if (slots.empty() || slots.size() >= slot_budget) {
        return bytes_op(text, log);
      }
      return tree_op(op, root, slots, log);
    }
    return bytes_op(text, log);
  }

  /// Removes a key of a map, or an item of a list (the list is rebuilt without it).
  void delete_item(std::vector<Slot>& slots, std::vector<std::string>& log) {
    Slot s = choose(slots);
    log.push_back("delete " + s.path);
    if (s.in_map) {
      s.parent.remove(s.key);
      return;
    }
    YAML::Node seq(YAML::NodeType::Sequence);
    for (std::size_t i = 0; i < s.parent.size(); ++i) {
      if (i != s.index) {
        seq.push_back(s.parent[i]);
      }
    }
    Slot* up = nullptr; // the last slot holding the list, as the fuzzer always chose it
    for (Slot& o : slots) {
      if (o.node.is(s.parent)) {
        up = &o;
      }
    }
    if (up != nullptr) {
      assign(*up, seq);
    }
  }

  std::string tree_op(int op, YAML::Node& root, std::vector<Slot>& slots,
                      std::vector<std::string>& log) {
    auto find = [&](const std::string& path) -> Slot* {
      for (Slot& s : slots) {
        if (s.path == path) {
          return &s;
        }
      }
      return nullptr;
    };
    switch (op) {
    case 0: // delete a key or a list item
      delete_item(slots, log);
      break;
    case 1:
    case 2: { // replace a scalar (numbers more often: they carry the ranges)
      std::vector<Slot> scalars;
      for (const Slot& s : slots) {
        if (s.node.IsScalar()) {
          scalars.push_back(s);
        }
      }
      Slot s = scalars.empty() ? choose(slots) : choose(scalars);
      const YAML::Node v = weird_value(s.node);
      log.push_back(
          fmt::format("set {} = {}", s.path, v.IsScalar() ? pd::printable(v.Scalar()) : "<node>"));
      assign(s, v);
      break;
    }
    case 3: { // replace any node (maps and lists too)
      Slot s = choose(slots);
      log.push_back("replace node " + s.path);
      assign(s, weird_value(s.node));
      break;
    }
    case 4: { // spacing so fine that the scene asks for gigabytes (or 10^15 particles)
      if (Slot* s = find(".lattice.spacing")) {
        const double v = s->node.IsScalar() ? std::atof(s->node.Scalar().c_str()) : 0.01;
        const double w = v / std::pow(10.0, uniform(0.3, 5.0));
        log.push_back(fmt::format("spacing {} -> {}", v, w));
        assign(*s, YAML::Node(fmt::format("{}", w)));
      }
      break;
    }
    case 5: { // horizon factor: at the edge, large or absurd
      static const std::vector<std::string> m{"1",   "1.0000001", "0.999", "1.5", "10",   "41",
                                              "100", "1e4",       "1e8",   "1e9", "1e19", "1e300"};
      const std::string v = choose(m);
      log.push_back("horizon_factor = " + v);
      root["lattice"]["horizon_factor"] = v;
      break;
    }
    case 6: { // a box coordinate far out
      std::vector<Slot> coords;
      for (const Slot& s : slots) {
        if (s.node.IsScalar() && s.path.find("box") != std::string::npos) {
          coords.push_back(s);
        }
      }
      if (!coords.empty()) {
        Slot s = choose(coords);
        const double v = std::atof(s.node.Scalar().c_str());
        const double w = pick(4) == 0 ? (pick(2) == 0 ? 1e300 : -1e300)
                                      : (v == 0 ? 1 : v) * std::pow(10.0, uniform(1, 12));
        log.push_back(fmt::format("box coordinate {} = {}", s.path, w));
        assign(s, YAML::Node(fmt::format("{}", w)));
      }
      break;
    }
    case 7: { // the other ways of making particles, and cracks (issue 38)
      new_particles_or_crack(root, log);
      break;
    }
    default: { // duplicate a list item (duplicate names) or nest a value deeply
      std::vector<Slot> lists;
      for (const Slot& s : slots) {
        if (s.node.IsSequence() && s.node.size() > 0) {
          lists.push_back(s);
        }
      }
      if (!lists.empty() && pick(2) == 0) {
        Slot s = choose(lists);
        log.push_back("duplicate an item of " + s.path);
        s.node.push_back(YAML::Clone(s.node[0]));
      } else {
        Slot s = choose(slots);
        const int depth = pick(3) == 0 ? 3000 : 1 + pick(6);
        YAML::Node v = s.node;
        for (int i = 0; i < depth; ++i) {
          YAML::Node seq(YAML::NodeType::Sequence);
          seq.push_back(v);
          v = seq;
        }
        log.push_back(fmt::format("nest {} {} deep", s.path, depth));
        assign(s, v);
      }
      break;
    }
    }
    return emit(root);
  }

  /// The first body made a graded set or a particle file, or a crack added: values at the
  /// edges (counts that overflow, gradings that leave a zone no width, files that are no files).
  void new_particles_or_crack(YAML::Node& root, std::vector<std::string>& log) {
    YAML::Node bodies = root["bodies"];
    const int kind = pick(3);
    if (kind < 2 && bodies.IsSequence() && bodies.size() > 0 && bodies[0].IsMap()) {
      YAML::Node body = bodies[0];
      for (const char* key : {"box", "boxes", "cylinder", "sphere", "minus"}) {
        body.remove(key);
      }
      if (kind == 0) {
        static const std::vector<std::string> counts{"1",   "3",   "8", "40", "1000",
                                                     "1e6", "3.5", "0", "-1", "3000000"};
        static const std::vector<std::string> gradings{"1", "4", "1e6", "1e300", "0", "-1", "nan"};
        YAML::Node graded(YAML::NodeType::Map);
        if (pick(2) == 0) {
          graded["shape"] = "box";
          graded["box"] = YAML::Load(pick(4) == 0 ? "[[0, 0], [0, 1]]" : "[[0, 0], [1, 0.5]]");
          graded["grading"] = choose(gradings);
        } else {
          graded["focal_half_distance"] = pick(4) == 0 ? "0" : "0.0416667";
        }
        YAML::Node zones(YAML::NodeType::Sequence);
        zones.push_back(choose(counts));
        zones.push_back(choose(counts));
        graded["zones"] = zones;
        graded["pattern"] = choose(counts);
        log.push_back("graded body " + emit(graded));
        body["graded"] = graded;
      } else {
        const std::string path = choose(particle_files());
        log.push_back("particle body " + pd::printable(path));
        body["particles"] = path;
      }
      return;
    }
    static const std::vector<std::string> segments{
        "[[0.05, 0.05], [0.15, 0.05]]", "[[1e6, 1e6], [2e6, 1e6]]", "[[0, 0], [0, 0]]",
        "[[0, 0, 0], [1, 1, 1]]",       "[[nan, 0], [1, 0]]",       "[[0, 0]]",
        "[[0.05, 0.05], [0.05, 0.05]]"};
    YAML::Node crack(YAML::NodeType::Map);
    crack["name"] = "fuzz";
    const int where = pick(4);
    const YAML::Node spacing = root["lattice"]["spacing"];
    const double h = spacing.IsScalar() ? std::atof(spacing.Scalar().c_str()) : 0.0;
    if (where == 0 && std::isfinite(h) && h > 0) {
      // Through a row of particle centres (cell-centred lattice at the origin) or along the
      // cell face beside it: the first must be refused, the second cuts bonds.
      const double y = (pick(2) == 0 ? 1.5 : 2.0) * h;
      const bool three = root["dimension"].IsScalar() && root["dimension"].Scalar() == "3";
      if (three) {
        crack["polygon"] = YAML::Load(fmt::format(
            "[[{0}, {1}, {0}], [{2}, {1}, {0}], [{2}, {1}, {2}]]", 0.5 * h, y, 8.5 * h));
      } else {
        crack["segment"] = YAML::Load(fmt::format("[[{}, {}], [{}, {}]]", 0.5 * h, y, 8.5 * h, y));
      }
    } else if (where == 1) { // 3D: polygons, degenerate ones too
      static const std::vector<std::string> polygons{
          "[[0, 0.05, 0], [0.1, 0.05, 0], [0.1, 0.05, 0.1]]", "[[0, 0, 0], [0, 0, 0], [0, 0, 0]]",
          "[[0, 0, 0], [1, 1, 1], [2, 2, 2]]",
          "[[0, 0.05, 0], [0.1, 0.05, 0], [0.1, 0.06, 0.1], "
          "[0, 0.04, 0.1]]"};
      crack["polygon"] = YAML::Load(choose(polygons));
    } else {
      crack["segment"] = YAML::Load(choose(segments));
    }
    YAML::Node cracks =
        root["cracks"].IsSequence() ? root["cracks"] : YAML::Node(YAML::NodeType::Sequence);
    cracks.push_back(crack);
    root["cracks"] = cracks;
    log.push_back("crack " + emit(crack));
  }

  /// A small valid particle file, one with a NUL byte in a cell, and paths that are no files.
  static const std::vector<std::string>& particle_files() {
    static const std::vector<std::string> files = [] {
      const fs::path dir = fs::temp_directory_path();
      const fs::path good = dir / "pd-fuzz-particles.csv";
      const fs::path nul = dir / "pd-fuzz-particles-nul.csv";
      std::string csv = "x,y,volume\n";
      for (int j = 0; j < 8; ++j) {
        for (int i = 0; i < 8; ++i) {
          csv += fmt::format("{},{},1e-4\n", 0.01 * i, 0.01 * j);
        }
      }
      std::ofstream(good, std::ios::binary) << csv;
      std::ofstream(nul, std::ios::binary)
          << std::string("x,y,volume\n0,0,1e-4\n0.01,0") + '\0' + ",1e-4\n";
      return std::vector<std::string>{good.string(), nul.string(), "/nonexistent/p.csv",
                                      "/dev/zero", dir.string()};
    }();
    return files;
  }

  std::string bytes_op(std::string text, std::vector<std::string>& log) {
    std::vector<std::size_t> line_starts{0};
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n' && i + 1 < text.size()) {
        line_starts.push_back(i + 1);
      }
    }
    auto line_at = [&](std::size_t k) {
      const std::size_t a = line_starts[k];
      const std::size_t b = text.find('\n', a);
      return text.substr(a, b == std::string::npos ? std::string::npos : b - a + 1);
    };
    switch (pick(8)) {
    case 0: { // duplicate a line: duplicate keys, list items
      const std::size_t k = static_cast<std::size_t>(pick(static_cast<int>(line_starts.size())));
      log.push_back(fmt::format("duplicate line {}", k + 1));
      const std::string l = line_at(k);
      text.insert(line_starts[k], l.ends_with('\n') ? l : l + "\n");
      break;
    }
    case 1: { // truncate
      const std::size_t at = static_cast<std::size_t>(pick(static_cast<int>(text.size()) + 1));
      log.push_back(fmt::format("truncate at {}", at));
      text.resize(at);
      break;
    }
    case 2: { // flip bytes
      const int n = 1 + pick(8);
      for (int i = 0; i < n && !text.empty(); ++i) {
        const auto at = static_cast<std::size_t>(pick(static_cast<int>(text.size())));
        text[at] = static_cast<char>(text[at] ^ (1 + pick(255)));
      }
      log.push_back(fmt::format("flip {} bytes", n));
      break;
    }
    case 3: { // insert bytes, YAML syntax characters more often than others
      static const std::string syntax = ":-[]{},&*!|>'\"%@`#\t\n ?";
      const int n = 1 + pick(8);
      for (int i = 0; i < n; ++i) {
        const auto at = static_cast<std::size_t>(pick(static_cast<int>(text.size()) + 1));
        const char c = pick(2) == 0
                           ? syntax[static_cast<std::size_t>(pick(static_cast<int>(syntax.size())))]
                           : static_cast<char>(pick(256));
        text.insert(at, 1, c);
      }
      log.push_back(fmt::format("insert {} bytes", n));
      break;
    }
    case 4: { // delete a line
      const std::size_t k = static_cast<std::size_t>(pick(static_cast<int>(line_starts.size())));
      log.push_back(fmt::format("delete line {}", k + 1));
      text.erase(line_starts[k], line_at(k).size());
      break;
    }
    case 5: { // break the indentation of a line
      const std::size_t k = static_cast<std::size_t>(pick(static_cast<int>(line_starts.size())));
      const int how = pick(3);
      log.push_back(fmt::format("indent line {} ({})", k + 1, how));
      if (how == 0) {
        text.insert(line_starts[k], "\t");
      } else if (how == 1) {
        text.insert(line_starts[k], std::string(static_cast<std::size_t>(1 + pick(5)), ' '));
      } else if (text.compare(line_starts[k], 2, "  ") == 0) {
        text.erase(line_starts[k], 2);
      }
      break;
    }
    case 6: { // an alias bomb: 9 levels of 9 aliases (9^9 leaves if expanded)
      std::string bomb = "\nbomb0: &b0 [1, 2]\n";
      for (int i = 1; i < 10; ++i) {
        bomb += fmt::format("bomb{}: &b{} [", i, i);
        for (int j = 0; j < 9; ++j) {
          bomb += fmt::format("{}*b{}", j > 0 ? ", " : "", i - 1);
        }
        bomb += "]\n";
      }
      static const std::vector<std::string> uses{"effects: *b9\n", "title: *b9\n", "probes: *b9\n",
                                                 "supports: *b9\n"};
      log.push_back("alias bomb");
      text += bomb + choose(uses);
      break;
    }
    default: { // a second document, or text appended
      static const std::vector<std::string> tails{
          "---\ndimension: 3\n",   "...\n", "\n- x\n", "\n: :\n", "\nlattice: {}\n",
          std::string("\0\0\0", 3)};
      log.push_back("append");
      text += choose(tails);
      break;
    }
    }
    return text;
  }
};

// ---------------------------------------------------------------------------------------------
// Watchdog: a case that runs longer than the limit is a hang; abort with its number.
// ---------------------------------------------------------------------------------------------

class Watchdog {
public:
  explicit Watchdog(double seconds) : limit_(seconds), thread_([this] { watch(); }) {}
  ~Watchdog() {
    stop_.store(true);
    thread_.join();
  }
  void start(std::size_t index) {
    index_.store(index);
    started_.store(now());
    running_.store(true);
  }
  void finish() { running_.store(false); }

private:
  static double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  void watch() {
    while (!stop_.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      if (running_.load() && now() - started_.load() > limit_) {
        std::fprintf(stderr, "scene fuzz: case %zu ran longer than %.0f s: a hang\n", index_.load(),
                     limit_);
        std::abort();
      }
    }
  }
  double limit_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> running_{false};
  std::atomic<std::size_t> index_{0};
  std::atomic<double> started_{0};
  std::thread thread_;
};

// ---------------------------------------------------------------------------------------------
// One case
// ---------------------------------------------------------------------------------------------

enum class Outcome { scene_error, refused_memory, ran, unstable, run_error, built, estimated };

struct Tally {
  std::map<Outcome, std::size_t> count;
  std::vector<std::string> run_errors; ///< clean exceptions after a valid parse
  double slowest = 0;
  std::size_t slowest_case = 0;
  double worst_memory_ratio = 0; ///< actual memory_bytes / estimate, over built models
};

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

/// "NAME:LINE:COL: error: WHAT\n  hint: HOW", each part non-empty and on one line.
bool well_formed(const std::string& message, const std::string& name) {
  if (message.rfind(name + ":", 0) != 0) {
    return false;
  }
  std::size_t at = name.size() + 1;
  for (int field = 0; field < 2; ++field) {
    const std::size_t digits = message.find_first_not_of("0123456789", at);
    if (digits == std::string::npos || digits == at || message[digits] != ':') {
      return false;
    }
    at = digits + 1;
  }
  const std::string error = " error: ";
  const std::string hint = "\n  hint: ";
  const std::size_t h = message.find(hint);
  return message.compare(at, error.size(), error) == 0 && h != std::string::npos &&
         h > at + error.size() && message.size() > h + hint.size() && message.find('\n', at) == h &&
         message.find('\n', h + 1) == std::string::npos;
}

/// Runs one case; returns an empty string if it behaved, else what went wrong.
std::string run_case(const std::string& name, const std::string& text, Tally& tally) {
  pd::Scene scene;
  try {
    scene = pd::parse_scene(text, name);
  } catch (const pd::SceneError& e) {
    const std::string message = e.what();
    if (!well_formed(message, name)) {
      return "SceneError without FILE:LINE:COL, message or hint:\n" + message;
    }
    if (message.size() > 4000) {
      return fmt::format("a SceneError of {} bytes echoes too much:\n{}", message.size(),
                         message.substr(0, 300));
    }
    if (message.find("internal error") != std::string::npos) {
      return "the parser hit an internal error:\n" + message;
    }
    tally.count[message.find("this scene needs about") != std::string::npos ||
                        message.find("32 bits") != std::string::npos
                    ? Outcome::refused_memory
                    : Outcome::scene_error]++;
    return {};
  } catch (const std::exception& e) {
    return fmt::format("parse_scene threw a non-SceneError exception: {}", e.what());
  }

  const pd::ResourceEstimate est = pd::estimate_resources(scene.model, scene.solver);
  try {
    if (est.particles <= 6000 && est.bytes <= 48.0 * (1 << 20)) {
      scene.solver.max_steps = std::min<std::size_t>(scene.solver.max_steps, 20);
      pd::RunOptions opt;
      opt.stop_on_interrupt = false;
      opt.write_vtu = false;
      opt.keep_final_field = true;
      const pd::RunOutcome out = pd::run_scene(scene, opt);
      if (static_cast<double>(out.particles) > est.particles) {
        return fmt::format("{} particles, estimate {}", out.particles, est.particles);
      }
      if (out.result.status == pd::RunStatus::unstable) {
        if (out.result.message.empty()) {
          return "an unstable run without a message";
        }
        tally.count[Outcome::unstable]++;
        return {};
      }
      std::vector<double> probes;
      for (const auto& [p, v] : out.probes) {
        probes.push_back(v);
      }
      if (!all_finite(out.displacement) || !all_finite(probes) ||
          !std::isfinite(out.result.kinetic_energy) || !std::isfinite(out.result.strain_energy)) {
        return fmt::format("status {} but non-finite results", pd::to_string(out.result.status));
      }
      tally.count[Outcome::ran]++;
    } else if (est.particles <= 40000 && est.bytes <= 96.0 * (1 << 20)) {
      const pd::Model model = pd::build_model(scene.model);
      if (static_cast<double>(model.size()) > est.particles) {
        return fmt::format("{} particles, estimate {}", model.size(), est.particles);
      }
      tally.worst_memory_ratio =
          std::max(tally.worst_memory_ratio,
                   static_cast<double>(model.memory_bytes()) / std::max(est.model_bytes, 1.0));
      tally.count[Outcome::built]++;
    } else {
      tally.count[Outcome::estimated]++;
    }
  } catch (const std::exception& e) {
    const std::string what = e.what();
    if (what.empty()) {
      return "a run threw an exception without a message";
    }
    tally.run_errors.push_back(name + ": " + what);
    tally.count[Outcome::run_error]++;
  }
  return {};
}

std::string case_name(std::size_t index, const ShippedScene& base) {
  return fmt::format("fuzz-{}-{}", index, base.name);
}

TEST(SceneFuzz, MutatedShippedScenes) {
  // The guard must refuse the same cases on every machine: fix the memory it may assume.
  setenv("PD_MEMORY_LIMIT", "1G", 0);
  const auto& scenes = shipped_scenes();
  ASSERT_GE(scenes.size(), 5u) << "shipped scenes not found in " << PD_SCENES_DIR;
  const char* only = std::getenv("PD_FUZZ_ONLY");
  const bool single = only != nullptr && *only != '\0';
  const std::size_t cases = single ? 1 : env_size("PD_FUZZ_CASES", 300);
  const std::size_t first = single ? env_size("PD_FUZZ_ONLY", 0) : env_size("PD_FUZZ_FIRST", 0);
  const std::size_t seed = env_size("PD_FUZZ_SEED", 20261121);
  Watchdog watchdog(static_cast<double>(env_size("PD_FUZZ_CASE_SECONDS", 120)));
  Tally tally;
  std::size_t failures = 0;
  for (std::size_t c = first; c < first + cases; ++c) {
    const ShippedScene& base = scenes[c % scenes.size()];
    Mutator mutator(seed * 1000003ULL + c);
    std::vector<std::string> log;
    const std::string text = mutator.mutate(base.text, log);
    const std::string name = case_name(c, base);
    if (single) {
      fmt::print("--- case {} ({}): {}\n{}\n---\n", c, base.name, fmt::join(log, "; "), text);
    }
    if (std::getenv("PD_FUZZ_VERBOSE") != nullptr) {
      fmt::print(stderr, "case {} ({}): {}\n", c, base.name, fmt::join(log, "; "));
    }
    const auto t0 = std::chrono::steady_clock::now();
    watchdog.start(c);
    const std::string problem = run_case(name, text, tally);
    watchdog.finish();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (seconds > tally.slowest) {
      tally.slowest = seconds;
      tally.slowest_case = c;
    }
    if (!problem.empty()) {
      ++failures;
      ADD_FAILURE() << "case " << c << " (" << base.name << ": "
                    << fmt::format("{}", fmt::join(log, "; ")) << "): " << problem
                    << "\n  reproduce: PD_FUZZ_ONLY=" << c << " PD_FUZZ_SEED=" << seed;
    }
  }
  const auto n = [&](Outcome o) { return tally.count[o]; };
  fmt::print("scene fuzz: {} cases from seed {}: {} scene errors, {} refused by the memory guard, "
             "{} ran ({} unstable), {} run errors, {} only built, {} only estimated; "
             "slowest case {} took {:.2f} s; worst memory_bytes/estimate {:.3f}\n",
             cases, seed, n(Outcome::scene_error), n(Outcome::refused_memory),
             n(Outcome::ran) + n(Outcome::unstable), n(Outcome::unstable), n(Outcome::run_error),
             n(Outcome::built), n(Outcome::estimated), tally.slowest_case, tally.slowest,
             tally.worst_memory_ratio);
  for (const std::string& e : tally.run_errors) {
    fmt::print("  run error: {}\n", e);
  }
  EXPECT_EQ(failures, 0u);
  // The estimate may be high (bulk families at surfaces) but must not be low.
  EXPECT_LE(tally.worst_memory_ratio, 1.0);
}

} // namespace
