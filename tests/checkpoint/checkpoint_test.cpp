// Checkpoints: the file format refuses what it must (truncated, corrupted, foreign files, another
// scene), and a Simulation saved mid-run and restored into a fresh one continues bitwise like the
// run that never stopped, for every integrator that allows checkpoints. The end-to-end test of
// `pd run` killed with SIGKILL is kill_restart_test.py.
#include "libpd/app/run.hpp"
#include "libpd/io/checkpoint.hpp"
#include "libpd/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <iterator>
#include <tuple>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

/// A fresh folder per test, removed afterwards.
class TempDir {
public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() /
              ("pd-checkpoint-test-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

private:
  fs::path path_;
};

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << s;
}

/// The message of the CheckpointError that `f` throws ("" if it throws none).
template <class F>
std::string checkpoint_error(F&& f) {
  try {
    f();
  } catch (const pd::CheckpointError& e) {
    return e.what();
  }
  return "";
}

/// The dog-bone of the kill test (2D, ~800 particles, damage), pulled three times as far and ten
/// times as fast as there: bonds break from about step 100 to step 550.
pd::Scene dogbone(pd::IntegratorKind kind) {
  pd::Scene s = pd::load_scene(PD_CHECKPOINT_DIR "/dogbone.yaml");
  s.model.supports.at(1).displacement[0] = 3e-4;
  s.solver.ramp_time = 2e-4;
  s.solver.integrator = kind;
  if (kind != pd::IntegratorKind::damped_euler) {
    s.model.effects.damping = false;
    s.solver.damping = 0;
  }
  return s;
}

pd::Scene dogbone_arkode(pd::ArkodeTable table) {
  pd::Scene s = dogbone(pd::IntegratorKind::damped_euler);
  s.model.effects.damage = false; // arkode refuses damage
  for (auto& m : s.model.materials) {
    m.critical_stretch.reset();
  }
  s.solver.integrator = pd::IntegratorKind::arkode;
  s.solver.arkode.table = table;
  return s;
}

/// Everything a step reads or a summary reports, to compare bit for bit.
struct Snapshot {
  pd::State state;
  pd::BondState bonds;
  std::size_t force_evaluations = 0;
  std::size_t internal_steps = 0;
  pd::RunStatus status = pd::RunStatus::end_time;
};

Snapshot snapshot(const pd::Simulation& sim, const pd::RunResult& r) {
  return {sim.state(), sim.model().state, sim.integrator().force_evaluations(),
          sim.integrator().internal_steps(), r.status};
}

template <class T>
bool bitwise_equal(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

std::size_t broken_count(const pd::BondState& b) {
  return static_cast<std::size_t>(std::count(b.broken.begin(), b.broken.end(), 1));
}

void expect_bitwise_equal(const Snapshot& a, const Snapshot& b) {
  EXPECT_EQ(a.state.step, b.state.step);
  EXPECT_EQ(std::memcmp(&a.state.time, &b.state.time, sizeof(double)), 0);
  EXPECT_TRUE(bitwise_equal(a.state.position, b.state.position)) << "positions";
  EXPECT_TRUE(bitwise_equal(a.state.velocity, b.state.velocity)) << "velocities";
  EXPECT_TRUE(bitwise_equal(a.state.force, b.state.force)) << "forces";
  EXPECT_TRUE(bitwise_equal(a.bonds.broken, b.bonds.broken)) << "broken bonds";
  EXPECT_TRUE(bitwise_equal(a.bonds.damage, b.bonds.damage)) << "damage";
  EXPECT_TRUE(bitwise_equal(a.bonds.plastic_stretch, b.bonds.plastic_stretch)) << "plastic";
  EXPECT_EQ(a.force_evaluations, b.force_evaluations);
  EXPECT_EQ(a.internal_steps, b.internal_steps);
  EXPECT_EQ(a.status, b.status);
}

/// Run `total` steps (max_steps) in one go, and again as `split` steps, a checkpoint into memory, a
/// fresh model and Simulation restored from it and the rest of the run. max_steps counts from the
/// original start, so the restored run must stop at `total` too. Returns (uninterrupted, restored,
/// state at the split).
std::tuple<Snapshot, Snapshot, Snapshot> split_run(pd::Scene scene, std::size_t split,
                                                   std::size_t total) {
  scene.solver.end_time.reset();
  scene.solver.max_steps = total;
  pd::Model m1 = pd::build_model(scene.model);
  pd::Simulation straight(m1, scene.solver, scene.initial);
  const pd::RunResult r1 = straight.run();

  pd::Model m2 = pd::build_model(scene.model);
  pd::Simulation first(m2, scene.solver, scene.initial);
  const pd::RunResult r2 =
      first.run([&](const pd::Simulation& s) { return s.state().step < split; });
  pd::CheckpointWriter w;
  first.save(w);

  pd::Model m3 = pd::build_model(scene.model);
  pd::Simulation second(m3, scene.solver, scene.initial);
  pd::CheckpointReader r(w.data(), "memory");
  second.restore(r);
  r.finish();
  const pd::RunResult r3 = second.run();
  return {snapshot(straight, r1), snapshot(second, r3), snapshot(first, r2)};
}

} // namespace

TEST(CheckpointFormat, WriterReaderRoundTrip) {
  pd::CheckpointWriter w;
  w.section("ABCD");
  w.u64(42);
  w.f64(-0.0);
  w.string("héllo");
  w.doubles({1.5, -2.25, 1e-300});
  w.bytes({0, 1, 255});
  w.boolean(true);
  pd::CheckpointReader r(w.data(), "memory");
  r.section("ABCD");
  EXPECT_EQ(r.u64(), 42u);
  const double z = r.f64();
  EXPECT_TRUE(std::signbit(z)); // bits, not values: −0 stays −0
  EXPECT_EQ(r.string(), "héllo");
  EXPECT_EQ(r.doubles(), (std::vector<double>{1.5, -2.25, 1e-300}));
  EXPECT_EQ(r.bytes(), (std::vector<std::uint8_t>{0, 1, 255}));
  EXPECT_TRUE(r.boolean());
  EXPECT_NO_THROW(r.finish());
  // Reading on past the end, or a wrong section tag, is refused with the section's name.
  EXPECT_NE(checkpoint_error([&] { r.u64(); }).find("section 'ABCD'"), std::string::npos);
  pd::CheckpointReader r2(w.data(), "memory");
  EXPECT_NE(checkpoint_error([&] { r2.section("WXYZ"); }).find("expected section 'WXYZ'"),
            std::string::npos);
}

TEST(CheckpointFormat, FileRoundTripAndAtomicWrite) {
  TempDir dir("file");
  pd::CheckpointFingerprint f;
  f.scene = "a.yaml";
  f.add("particles", "12");
  pd::CheckpointWriter w;
  w.section("DATA");
  w.doubles({3.0, 4.0});
  const fs::path p = dir.path() / "c.pdcp";
  pd::write_checkpoint(p, f, w);
  pd::write_checkpoint(p, f, w); // overwriting goes through a temporary as well
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    names.push_back(e.path().filename().string());
  }
  EXPECT_EQ(names, std::vector<std::string>{"c.pdcp"}); // no temporary left behind
  pd::CheckpointReader r = pd::read_checkpoint(p, f);
  r.section("DATA");
  EXPECT_EQ(r.doubles(), (std::vector<double>{3.0, 4.0}));
  r.finish();
  EXPECT_EQ(pd::read_checkpoint_fingerprint(p).scene, "a.yaml");
}

// --- Damaged files ------------------------------------------------------------------------------

class DamagedCheckpoint : public ::testing::Test {
protected:
  void SetUp() override {
    scene_ = dogbone(pd::IntegratorKind::damped_euler);
    scene_.solver.end_time = 60 * 4.452e-7; // ~60 steps
    pd::RunOptions o;
    o.output_dir = dir_.path() / "run";
    o.write_vtu = false;
    o.checkpoint_every = 20;
    o.stop_on_interrupt = false;
    out_ = pd::run_scene(scene_, o);
    ASSERT_FALSE(out_.checkpoint.empty());
    good_ = read_bytes(out_.checkpoint);
    ASSERT_GT(good_.size(), 1000u);
  }
  /// run_scene restarted from `bytes` (written to a file first); returns the refusal message.
  std::string restart_with(const std::string& bytes, const pd::Scene& scene) {
    const fs::path p = dir_.path() / "bad.pdcp";
    write_bytes(p, bytes);
    pd::RunOptions o;
    o.restart = p;
    o.stop_on_interrupt = false;
    return checkpoint_error([&] { pd::run_scene(scene, o); });
  }
  std::string restart_with(const std::string& bytes) { return restart_with(bytes, scene_); }

  TempDir dir_{"damaged"};
  pd::Scene scene_;
  pd::RunOutcome out_;
  std::string good_;
};

TEST_F(DamagedCheckpoint, IntactFileIsAccepted) {
  EXPECT_EQ(restart_with(good_), "");
}

TEST_F(DamagedCheckpoint, TruncatedFileIsRefused) {
  for (std::size_t keep : {good_.size() - 1, good_.size() / 2, std::size_t{40}, std::size_t{8}}) {
    const std::string msg = restart_with(good_.substr(0, keep));
    EXPECT_NE(msg.find("is truncated"), std::string::npos) << keep << ": " << msg;
    EXPECT_NE(msg.find("bad.pdcp"), std::string::npos) << msg;
  }
  EXPECT_NE(restart_with("").find("is not a libpd checkpoint"), std::string::npos);
}

TEST_F(DamagedCheckpoint, FlippedByteIsRefused) {
  // One flipped bit anywhere in the payload or the fingerprint: the checksum catches it.
  for (std::size_t at : {std::size_t{40}, good_.size() / 3, good_.size() / 2, good_.size() - 9}) {
    std::string bad = good_;
    bad[at] = static_cast<char>(bad[at] ^ 0x01);
    const std::string msg = restart_with(bad);
    EXPECT_NE(msg.find("is corrupt"), std::string::npos) << at << ": " << msg;
  }
  std::string foreign = good_;
  foreign[0] = 'X';
  EXPECT_NE(restart_with(foreign).find("is not a libpd checkpoint"), std::string::npos);
  std::string newer = good_;
  newer[8] = static_cast<char>(newer[8] + 1); // format version 3
  EXPECT_NE(restart_with(newer).find("has format version 3; this pd reads version 2"),
            std::string::npos);
}

TEST_F(DamagedCheckpoint, OtherSceneIsRefused) {
  // Finer lattice: other particle and bond counts, named in the message with both values.
  pd::Scene finer = scene_;
  finer.model.lattice.spacing = 0.002;
  const pd::Model fm = pd::build_model(finer.model);
  std::string msg = restart_with(good_, finer);
  EXPECT_NE(msg.find("was written for scene"), std::string::npos) << msg;
  EXPECT_NE(
      msg.find(fmt::format("particles (checkpoint {}, this run {})", out_.particles, fm.size())),
      std::string::npos)
      << msg;
  EXPECT_NE(msg.find("bonds (checkpoint"), std::string::npos) << msg;

  // Same model, other time step (safety factor).
  pd::Scene other_dt = scene_;
  other_dt.solver.safety = 0.7;
  msg = restart_with(good_, other_dt);
  EXPECT_NE(msg.find("differs in: dt (checkpoint"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("particles ("), std::string::npos) << msg;

  // Same everything but a stiffer material: only the model hash tells.
  pd::Scene stiffer = scene_;
  stiffer.model.materials.at(0).youngs_modulus *= 1.0000001;
  stiffer.solver.dt = 4.452e-7;
  pd::Scene fixed_dt = scene_;
  fixed_dt.solver.dt = 4.452e-7;
  {
    pd::RunOptions o;
    o.output_dir = dir_.path() / "fixed";
    o.write_vtu = false;
    o.checkpoint_every = 20;
    o.stop_on_interrupt = false;
    const pd::RunOutcome fo = pd::run_scene(fixed_dt, o);
    msg = restart_with(read_bytes(fo.checkpoint), stiffer);
  }
  EXPECT_NE(msg.find("model_hash (checkpoint"), std::string::npos) << msg;

  // Another integrator.
  msg = restart_with(good_, dogbone(pd::IntegratorKind::verlet));
  EXPECT_NE(msg.find("integrator (checkpoint damped-euler, this run verlet)"), std::string::npos)
      << msg;

  // Stop criteria may change: a longer end_time extends the run.
  pd::Scene longer = scene_;
  longer.solver.end_time = 2 * *scene_.solver.end_time;
  EXPECT_EQ(restart_with(good_, longer), "");
}

// --- State round trip ---------------------------------------------------------------------------

TEST(CheckpointRoundTrip, DampedEulerWithDamage) {
  const auto [straight, restored, at_split] =
      split_run(dogbone(pd::IntegratorKind::damped_euler), 250, 600);
  // Bonds break before the checkpoint and after it: history is part of what was carried over.
  EXPECT_GT(broken_count(at_split.bonds), 0u);
  EXPECT_GT(broken_count(straight.bonds), broken_count(at_split.bonds));
  expect_bitwise_equal(straight, restored);
  EXPECT_EQ(restored.state.step, 600u);
  EXPECT_EQ(restored.status, pd::RunStatus::max_steps);
}

TEST(CheckpointRoundTrip, VerletWithDamage) {
  const auto [straight, restored, at_split] =
      split_run(dogbone(pd::IntegratorKind::verlet), 250, 600);
  EXPECT_GT(broken_count(at_split.bonds), 0u);
  EXPECT_GT(broken_count(straight.bonds), broken_count(at_split.bonds));
  expect_bitwise_equal(straight, restored);
  // Verlet reuses the last force: one evaluation per step plus the first.
  EXPECT_EQ(restored.force_evaluations, 601u);
}

TEST(CheckpointRoundTrip, AdrWithDamage) {
  const auto [straight, restored, at_split] = split_run(dogbone(pd::IntegratorKind::adr), 250, 600);
  EXPECT_GT(broken_count(straight.bonds), 0u);
  expect_bitwise_equal(straight, restored);
}

TEST(CheckpointRoundTrip, ArkodeFixedSteps) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  // rk4 (#311 work-around: reset every step), knoth-wolke (c_s ≠ 1), and the FSAL tables, whose
  // first stage the uninterrupted run copies while the restored one recomputes it.
  for (pd::ArkodeTable t : {pd::ArkodeTable::rk4, pd::ArkodeTable::knoth_wolke,
                            pd::ArkodeTable::bogacki_shampine, pd::ArkodeTable::dormand_prince}) {
    SCOPED_TRACE(pd::to_string(t));
    const auto [straight, restored, at_split] = split_run(dogbone_arkode(t), 40, 100);
    expect_bitwise_equal(straight, restored);
    EXPECT_EQ(restored.internal_steps, 100u);
  }
}

TEST(CheckpointRoundTrip, AdaptiveArkodeIsRefused) {
  if (!pd::arkode_available()) {
    GTEST_SKIP() << "built without SUNDIALS";
  }
  pd::Scene s = dogbone_arkode(pd::ArkodeTable::dormand_prince);
  s.solver.arkode.adaptive = true;
  s.solver.end_time = 1e-6;
  pd::RunOptions o;
  o.checkpoint = fs::temp_directory_path() / "pd-never-written.pdcp";
  o.checkpoint_every = 10;
  const std::string msg = checkpoint_error([&] { pd::run_scene(s, o); });
  EXPECT_NE(msg.find("adaptive ARKode steps cannot be checkpointed"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(o.checkpoint));
  // Without checkpoints the same run is fine.
  EXPECT_EQ(checkpoint_error([&] { pd::run_scene(s, pd::RunOptions{}); }), "");
}
