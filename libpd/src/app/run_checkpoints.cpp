// The checkpoint policy of a run: fingerprint, file, frequency, and the run's record beside the
// simulation's state.
#include "libpd/app/run_checkpoints.hpp"

#include "libpd/core/atomic_file.hpp"

#include <fmt/format.h>
#include <functional>
#include <unistd.h>

namespace pd {

namespace {

std::string hex(std::uint64_t v) {
  return fmt::format("{:016x}", v);
}

/// Everything build_model derived from the scene that the forces, the integrator and the
/// constraints read; two runs with equal hashes integrate the same equations.
std::uint64_t model_hash(const Model& m) {
  Fnv1a h;
  h.add_vector(m.particles.position);
  h.add_vector(m.particles.volume);
  h.add_vector(m.particles.material);
  h.add_vector(m.density);
  h.add_vector(m.family.offsets);
  h.add_vector(m.family.neighbour);
  h.add_vector(m.family.inverse_length);
  h.add_value(m.field.stiffness);
  h.add_value(m.field.critical_stretch);
  h.add_value(m.field.yield_stretch);
  h.add_vector(m.field.bond_stiffness);
  h.add_vector(m.field.bond_critical_stretch);
  h.add_vector(m.field.bond_yield_stretch);
  h.add_value(static_cast<std::uint64_t>(m.constraints.size()));
  for (const Constraint& c : m.constraints) { // field by field: the struct has padding
    h.add_value(c.particle);
    h.add_value(c.component);
    h.add_value(c.value);
    h.add_value(c.mirror_of);
    h.add_value(c.mirror_sign);
  }
  h.add_value(static_cast<std::uint64_t>(m.ghost_count));
  h.add_vector(m.extrapolated.particle);
  h.add_vector(m.extrapolated.offsets);
  h.add_vector(m.extrapolated.source);
  h.add_vector(m.extrapolated.coefficient);
  h.add_vector(m.extrapolated.negated);
  h.add_vector(m.external_force_density);
  return h.value();
}

void save_history(CheckpointWriter& w, const ProbeHistory& history,
                  const std::vector<VtuFrame>& frames) {
  w.section("HIST");
  w.doubles(history.time);
  for (const auto& row : history.values) {
    w.doubles(row);
  }
  w.section("VTUF");
  w.u64(frames.size());
  for (const auto& [t, name] : frames) {
    w.f64(t);
    w.string(name);
  }
}

void restore_history(CheckpointReader& r, std::size_t columns, ProbeHistory& history,
                     std::vector<VtuFrame>& frames) {
  r.section("HIST");
  history.time = r.doubles();
  history.values.clear();
  for (std::size_t k = 0; k < history.time.size(); ++k) {
    history.values.push_back(r.doubles(columns, "a probe history row"));
  }
  r.section("VTUF");
  const std::uint64_t n = r.u64();
  frames.clear();
  for (std::uint64_t k = 0; k < n; ++k) {
    const double t = r.f64();
    frames.push_back({t, r.string()});
  }
  r.finish();
}

} // namespace

std::filesystem::path rank_file(const std::filesystem::path& path, int rank, int ranks) {
  if (ranks == 1 || path.empty()) {
    return path;
  }
  std::filesystem::path out = path;
  out.replace_filename(fmt::format("{}-r{:04d}of{:04d}{}", path.stem().string(), rank, ranks,
                                   path.extension().string()));
  return out;
}

std::filesystem::path rank_file(const std::filesystem::path& path, const Communicator& comm) {
  return rank_file(path, comm.rank(), comm.size());
}

std::filesystem::path checkpoint_base_path(const RunOptions& options) {
  if (!options.checkpoint.empty()) {
    return options.checkpoint;
  }
  return options.output_dir.empty() ? std::filesystem::path{}
                                    : options.output_dir / "checkpoint.pdcp";
}

std::filesystem::path checkpoint_path(const RunOptions& options) {
  return rank_file(checkpoint_base_path(options),
                   options.communicator != nullptr ? *options.communicator : serial_communicator());
}

CheckpointFingerprint run_fingerprint(const Scene& scene, const Simulation& sim,
                                      const std::vector<ResolvedProbe>& probes) {
  const Model& m = sim.model();
  CheckpointFingerprint f;
  f.scene = scene.path.empty() ? scene.title : scene.path;
  f.add("dimension", std::to_string(m.spec.dimension.dim));
  f.add("particles", std::to_string(m.size()));
  f.add("bonds", std::to_string(m.family.bond_count()));
  f.add("integrator", sim.integrator().name());
  if (scene.solver.integrator == IntegratorKind::arkode) {
    const ArkodeSpec& a = scene.solver.arkode;
    f.add("arkode", fmt::format("adaptive={} rtol={} atol={} issue_311_workaround={}", a.adaptive,
                                exact_text(a.rtol), exact_text(a.atol), a.issue_311_workaround));
  }
  f.add("kernel", sim.forces().description());
  std::string effects;
  for (const auto& e : m.effects.names()) {
    effects += (effects.empty() ? "" : ",") + e;
  }
  f.add("effects", effects);
  f.add("dt", exact_text(sim.dt()));
  f.add("damping", exact_text(scene.solver.damping));
  f.add("ramp_time", exact_text(scene.solver.ramp_time));
  f.add("model_hash", hex(model_hash(m)));
  Fnv1a ph;
  std::string names;
  for (const auto& p : probes) {
    names += (names.empty() ? "" : ",") + p.name;
    ph.add_value(p.component);
    ph.add_vector(p.particles);
  }
  f.add("probes", names + " #" + hex(ph.value()));
  f.add("history_every", std::to_string(scene.output.history_every));
  return f;
}

std::filesystem::path next_piece(const std::filesystem::path& piece) {
  return piece.string() + ".next";
}

std::filesystem::path set_marker(const std::filesystem::path& base) {
  return base.string() + ".complete";
}

namespace {

/// Renames or removes, then makes that durable: the set on disk is what a restart will see.
void durably(const std::filesystem::path& folder_of, const std::function<void()>& change) {
  change();
  const int fd = open_folder(folder_of.parent_path());
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

void promote(const std::filesystem::path& next, const std::filesystem::path& piece) {
  std::error_code ec;
  durably(piece, [&] { std::filesystem::rename(next, piece, ec); });
  if (ec) {
    throw CheckpointError(
        fmt::format("cannot rename {} to {}: {}", next.string(), piece.string(), ec.message()));
  }
}

void remove_durably(const std::filesystem::path& file) {
  std::error_code ec;
  durably(file, [&] { std::filesystem::remove(file, ec); });
  if (ec) {
    throw CheckpointError(fmt::format("cannot remove {}: {}", file.string(), ec.message()));
  }
}

} // namespace

void recover_checkpoint_set(const std::filesystem::path& base, const Communicator& comm) {
  if (comm.size() == 1) {
    return; // one file, replaced atomically
  }
  const std::filesystem::path mine = rank_file(base, comm);
  std::error_code ec;
  const bool complete = std::filesystem::exists(set_marker(base), ec);
  comm.barrier(); // every rank has seen the marker before it goes
  if (std::filesystem::exists(next_piece(mine), ec)) {
    if (complete) {
      promote(next_piece(mine), mine);
    } else {
      remove_durably(next_piece(mine)); // an incomplete newer set: the one in place stands
    }
  }
  comm.barrier();
  if (comm.root() && complete) {
    remove_durably(set_marker(base));
  }
  comm.barrier();
}

CheckpointPolicy::CheckpointPolicy(const RunOptions& options, std::string refusal)
    : comm_(options.communicator != nullptr ? options.communicator : &serial_communicator()),
      base_(checkpoint_base_path(options)), file_(checkpoint_path(options)),
      every_(options.checkpoint_every), file_given_(!options.checkpoint.empty()),
      refusal_(std::move(refusal)) {
  if (every_ > 0 && file_.empty()) {
    throw CheckpointError("checkpoints need a file: give an output folder or a checkpoint path");
  }
  if (!refusal_.empty() && (every_ > 0 || file_given_ || !options.restart.empty())) {
    throw CheckpointError(fmt::format("cannot checkpoint this run: {}", refusal_));
  }
}

bool CheckpointPolicy::wanted_at_end(RunStatus status) const {
  if (status == RunStatus::unstable || file_.empty()) {
    return false;
  }
  return status == RunStatus::interrupted || every_ > 0 || file_given_;
}

void CheckpointPolicy::save(const CheckpointFingerprint& fingerprint, const Simulation& sim,
                            const ProbeHistory& history,
                            const std::vector<VtuFrame>& frames) const {
  CheckpointWriter w;
  sim.save(w);
  save_history(w, history, frames);
  if (comm_->size() == 1) {
    write_checkpoint(file_, fingerprint, w);
    return;
  }
  // Each barrier orders one phase on every rank before the next (see next_piece).
  write_checkpoint(next_piece(file_), fingerprint, w);
  comm_->barrier();
  if (comm_->root()) {
    write_file_atomically(set_marker(base_), "", Durability::synced);
  }
  comm_->barrier();
  promote(next_piece(file_), file_);
  comm_->barrier();
  if (comm_->root()) {
    remove_durably(set_marker(base_));
  }
  comm_->barrier(); // no rank starts a newer next piece while the marker still stands
}

void CheckpointPolicy::restore(const std::filesystem::path& path,
                               const CheckpointFingerprint& fingerprint, std::size_t probe_count,
                               Simulation& sim, ProbeHistory& history,
                               std::vector<VtuFrame>& frames) {
  CheckpointReader reader = read_checkpoint(path, fingerprint);
  sim.restore(reader);
  restore_history(reader, probe_count, history, frames);
}

} // namespace pd
