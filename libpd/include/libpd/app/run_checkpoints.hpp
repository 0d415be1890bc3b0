// The checkpoint policy of a run: which file, how often, what makes two runs the same
// (the fingerprint), and what a checkpoint carries beside the simulation's state (the probe
// history and the VTU frames written so far). The file format itself is io/checkpoint.hpp.
#pragma once

#include "libpd/app/probes.hpp"
#include "libpd/app/run_options.hpp"
#include "libpd/app/run_output.hpp"
#include "libpd/io/checkpoint.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <cstddef>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace pd {

/// What makes a run, for checkpoints: sizes, Δt, integrator, kernel, effects, damping, ramp, probes
/// and a hash of the model's arrays (positions, volumes, bonds, bond parameters, supports, loads).
/// Stop criteria (end_time, max_steps, steady) and output settings other than history_every are
/// left out, so a restart may extend a run.
CheckpointFingerprint run_fingerprint(const Scene& scene, const Simulation& sim,
                                      const std::vector<ResolvedProbe>& probes);

/// Default checkpoint path of a run: options.checkpoint, else output_dir/checkpoint.pdcp (empty
/// if neither is set).
std::filesystem::path checkpoint_path(const RunOptions& options);
/// A run split over N > 1 ranks keeps one checkpoint file per rank: NAME-rRRRRofNNNN.EXT beside
/// the path given (each written atomically). A restart on any number of ranks reads them all.
std::filesystem::path rank_file(const std::filesystem::path& path, int rank, int ranks);
std::filesystem::path rank_file(const std::filesystem::path& path, const Communicator& comm);
/// The path asked for (RunOptions::checkpoint, or output_dir/checkpoint.pdcp), before any rank
/// suffix.
std::filesystem::path checkpoint_base_path(const RunOptions& options);

/// A split run's checkpoint set is replaced in two phases, so that a rank killed at any moment
/// leaves a complete set: every rank writes its new piece to next_piece(piece); once all have,
/// rank 0 creates set_marker(base) (the new set is complete); every rank renames its next piece
/// into place; rank 0 removes the marker. A restart first finishes or undoes an interrupted
/// replacement (recover_checkpoint_set): with the marker the next pieces are the set, without
/// it the pieces in place are.
std::filesystem::path next_piece(const std::filesystem::path& piece);
std::filesystem::path set_marker(const std::filesystem::path& base);
/// On every rank of `comm` (collective), before the pieces of `base` (a set written on `ranks`
/// ranks, any number) are read.
void recover_checkpoint_set(const std::filesystem::path& base, int ranks, const Communicator& comm);

/// The rank counts of the checkpoint sets of `base` on disk (1: the single file `base`; N > 1: a
/// set of pieces NAME-rRRRRofNNNN.EXT, or their next pieces while one is replaced). Not
/// collective: what a check before the run may ask.
std::set<int> checkpoint_sets_on_disk(const std::filesystem::path& base);

/// The number of ranks that wrote the checkpoint set of `base` found on disk (collective; 1: the
/// single file `base`): this run's own rank count if a set of it is there, else the one set
/// there is. None, or several of other counts, is refused (CheckpointError).
int checkpoint_set_ranks(const std::filesystem::path& base, const Communicator& comm);
/// The files of the set of `base` written on `ranks` ranks, in rank order.
std::vector<std::filesystem::path> checkpoint_set(const std::filesystem::path& base, int ranks);

class CheckpointPolicy {
public:
  /// Refuses up front (CheckpointError) what cannot be continued bitwise, rather than after
  /// hours: checkpoints without a file, and any checkpoint option when the integrator gives a
  /// `refusal` (why its state cannot be saved).
  CheckpointPolicy(const RunOptions& options, std::string refusal);

  const std::filesystem::path& file() const { return file_; }
  std::size_t every() const { return every_; }
  const std::string& refusal() const { return refusal_; }

  /// A periodic checkpoint after this step.
  bool due(std::size_t step) const { return every_ > 0 && step % every_ == 0; }
  /// A checkpoint of the final state: Ctrl-C loses nothing, and a finished run can be extended
  /// (restart with a later end_time). An unstable state is never saved; the last good checkpoint
  /// stays.
  bool wanted_at_end(RunStatus status) const;

  /// Write the simulation's state with the run's record so far.
  void save(const CheckpointFingerprint& fingerprint, const Simulation& sim,
            const ProbeHistory& history, const std::vector<VtuFrame>& frames) const;
  /// Read the set `pieces` (each must match `fingerprint`) into the simulation and the run's
  /// record (a history of `probe_count` columns): each process takes the values of its particles
  /// from the pieces that own them, whatever number of ranks wrote the set.
  static void restore(const std::vector<std::filesystem::path>& pieces,
                      const CheckpointFingerprint& fingerprint, std::size_t probe_count,
                      Simulation& sim, ProbeHistory& history, std::vector<VtuFrame>& frames);

private:
  const Communicator* comm_;
  std::filesystem::path base_;
  std::filesystem::path file_;
  std::size_t every_ = 0;
  bool file_given_ = false;
  std::string refusal_;
};

} // namespace pd
