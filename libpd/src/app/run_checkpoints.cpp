// The checkpoint policy of a run: fingerprint, file, frequency, and the run's record beside the
// simulation's state.
#include "libpd/app/run_checkpoints.hpp"

#include "libpd/core/atomic_file.hpp"

#include <cctype>
#include <cstdio>
#include <fmt/format.h>
#include <functional>
#include <set>
#include <unistd.h>

namespace pd {

namespace {

std::string hex(std::uint64_t v) {
  return fmt::format("{:016x}", v);
}

/// The whole model's particle counts, on any rank.
std::size_t global_particles(const Model& m) {
  return m.ownership.partial() ? m.ownership.global_particles : m.size();
}
std::size_t global_body_particles(const Model& m) {
  return m.ownership.partial() ? m.ownership.global_body_particles : m.size() - m.ghost_count;
}

/// Everything build_model derived from the scene that the forces, the integrator and the
/// constraints read; two runs with equal hashes integrate the same equations. The same on any
/// number of ranks: each owned particle's own data (keyed by its global index, its bond row by
/// the neighbours' global indices) is hashed alone and the hashes are added, an order-free sum.
std::uint64_t model_hash(const Model& m) {
  const Ownership& own = m.ownership;
  const auto global = [&](std::uint32_t i) { return own.global(i); };
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (!own.owns(i)) {
      continue;
    }
    Fnv1a h;
    h.add_value(global(static_cast<std::uint32_t>(i)));
    h.add_value(m.particles.position[i]);
    h.add_value(m.particles.volume[i]);
    h.add_value(m.particles.material[i]);
    h.add_value(m.density[i]);
    for (std::size_t k = m.family.offsets[i]; k < m.family.offsets[i + 1]; ++k) {
      h.add_value(global(m.family.neighbour[k]));
      h.add_value(m.family.inverse_length[k]);
      for (const std::vector<double>* per_bond :
           {&m.field.bond_stiffness, &m.field.bond_critical_stretch, &m.field.bond_yield_stretch}) {
        if (!per_bond->empty()) {
          h.add_value((*per_bond)[k]);
        }
      }
    }
    if (!m.external_force_density.empty()) {
      for (std::size_t c = 0; c < 3; ++c) {
        h.add_value(m.external_force_density[3 * i + c]);
      }
    }
    sum += h.value();
  }
  for (const Constraint& c : m.constraints) { // field by field: the struct has padding
    if (own.owns(c.particle)) {
      Fnv1a h;
      h.add_value(global(c.particle));
      h.add_value(c.component);
      h.add_value(c.value);
      h.add_value(c.mirror_of == Constraint::no_mirror ? c.mirror_of : global(c.mirror_of));
      h.add_value(c.mirror_sign);
      sum += h.value();
    }
  }
  const ExtrapolatedParticles& e = m.extrapolated;
  for (std::size_t d = 0; d < e.particle.size(); ++d) {
    if (own.owns(e.particle[d])) {
      Fnv1a h;
      h.add_value(global(e.particle[d]));
      for (std::size_t t = e.offsets[d]; t < e.offsets[d + 1]; ++t) {
        h.add_value(global(e.source[t]));
        h.add_value(e.coefficient[t]);
        h.add_value(e.negated.empty() ? std::uint8_t{0} : e.negated[t]); // empty: none negated
      }
      sum += h.value();
    }
  }
  Fnv1a h;
  h.add_value(own.communicator().sum(sum));
  h.add_value(m.field.stiffness);
  h.add_value(m.field.critical_stretch);
  h.add_value(m.field.yield_stretch);
  h.add_value(static_cast<std::uint64_t>(global_particles(m) - global_body_particles(m)));
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
  const Ownership& own = m.ownership;
  std::uint64_t directed = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    directed += own.owns(i) ? m.family.family_size(i) : 0;
  }
  f.add("particles", std::to_string(global_particles(m)));
  f.add("bonds", std::to_string(own.communicator().sum(directed) / 2));
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
    std::uint64_t particles = 0; // by global index, order-free: the same on any rank count
    for (std::size_t k = 0; k < p.particles.size(); ++k) {
      Fnv1a one;
      one.add_value(own.global(p.particles[k]));
      one.add_value(p.role.empty() ? std::uint8_t{0} : p.role[k]);
      particles += one.value();
    }
    ph.add_value(own.communicator().sum(particles));
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

std::set<int> checkpoint_sets_on_disk(const std::filesystem::path& base) {
  // Pieces are NAME-rRRRRofNNNN.EXT (rank_file), or their next pieces while a set is replaced.
  const std::string stem = base.stem().string() + "-r";
  const std::string ext = base.extension().string();
  std::set<int> counts;
  std::error_code ec;
  if (std::filesystem::is_regular_file(base, ec)) {
    counts.insert(1);
  }
  const std::filesystem::path folder =
      base.parent_path().empty() ? std::filesystem::path(".") : base.parent_path();
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    std::string name = entry.path().filename().string();
    if (name.ends_with(".next")) {
      name.resize(name.size() - 5);
    }
    int rank = 0, ranks = 0;
    char of[3] = {};
    if (name.starts_with(stem) && name.ends_with(ext) &&
        name.size() == stem.size() + 4 + 2 + 4 + ext.size() &&
        std::sscanf(name.c_str() + stem.size(), "%4d%2c%4d", &rank, of, &ranks) == 3 &&
        std::string_view(of, 2) == "of" && ranks > 1 && rank < ranks) {
      counts.insert(ranks);
    }
  }
  return counts;
}

int checkpoint_set_ranks(const std::filesystem::path& base, const Communicator& comm) {
  std::string found;
  if (comm.root()) {
    const std::set<int> counts = checkpoint_sets_on_disk(base);
    if (counts.contains(comm.size()) || counts.empty()) {
      // This run's own count first, as before sets of other counts could be read; with nothing
      // there, reading its pieces names the file missing.
      found = std::to_string(comm.size());
    } else if (counts.size() == 1) {
      found = std::to_string(*counts.begin());
    } else {
      std::string list;
      for (const int n : counts) {
        list += (list.empty() ? "" : ", ") + std::to_string(n);
      }
      found = fmt::format("checkpoint sets of {} written on {} ranks lie side by side and none "
                          "on {}: remove the ones not meant",
                          base.string(), list, comm.size());
    }
  }
  found = comm.broadcast(found);
  if (found.empty() || !std::isdigit(static_cast<unsigned char>(found.front()))) {
    throw CheckpointError(found);
  }
  return std::stoi(found);
}

std::vector<std::filesystem::path> checkpoint_set(const std::filesystem::path& base, int ranks) {
  std::vector<std::filesystem::path> pieces;
  for (int r = 0; r < ranks; ++r) {
    pieces.push_back(rank_file(base, r, ranks));
  }
  return pieces;
}

void recover_checkpoint_set(const std::filesystem::path& base, int ranks,
                            const Communicator& comm) {
  if (ranks == 1) {
    return; // one file, replaced atomically
  }
  std::error_code ec;
  const bool complete = std::filesystem::exists(set_marker(base), ec);
  comm.barrier(); // every rank has seen the marker before it goes
  // The set may have been written on another number of ranks: rank r sees to pieces r, r + M, ...
  for (int piece = comm.rank(); piece < ranks; piece += comm.size()) {
    const std::filesystem::path p = rank_file(base, piece, ranks);
    if (std::filesystem::exists(next_piece(p), ec)) {
      if (complete) {
        promote(next_piece(p), p);
      } else {
        remove_durably(next_piece(p)); // an incomplete newer set: the one in place stands
      }
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

void CheckpointPolicy::restore(const std::vector<std::filesystem::path>& pieces,
                               const CheckpointFingerprint& fingerprint, std::size_t probe_count,
                               Simulation& sim, ProbeHistory& history,
                               std::vector<VtuFrame>& frames) {
  CheckpointReader reader = read_checkpoint_set(pieces, fingerprint);
  sim.restore(reader);
  restore_history(reader, probe_count, history, frames);
}

} // namespace pd
