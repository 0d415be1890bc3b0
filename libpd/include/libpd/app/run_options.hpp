// What a caller asks of a run of a scene: where to write, what to show, when to checkpoint and
// what to continue from. Its own header so that the run's parts (checkpoint policy, output) read
// it without depending on the run itself.
#pragma once

#include "libpd/core/communicator.hpp"
#include "libpd/discretisation/distribution.hpp"

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

namespace pd {

struct RunOptions {
  std::filesystem::path output_dir; ///< empty: write nothing
  bool progress = false;            ///< progress line on stderr
  bool write_vtu = true;
  bool stop_on_interrupt = true; ///< SIGINT/TERM/HUP end the run cleanly, status `interrupted`
  /// An output folder holding another run's files (its manifest) is refused unless this is set;
  /// then exactly the files that manifest lists are removed first (app/output_folder.hpp).
  bool overwrite = false;
  /// Called with each warning about the run's set-up as soon as it is known (before the run);
  /// the warnings also go into RunOutcome::warnings and summary.json.
  std::function<void(const std::string&)> on_warning;
  bool keep_final_field = false; ///< return reference positions and final displacements
  /// Checkpoints (checkpoint.hpp): the complete run state every `checkpoint_every` steps (0:
  /// never), at the end of such a run, and when SIGINT interrupts any run that has a checkpoint
  /// path. The path is `checkpoint`, or output_dir/checkpoint.pdcp if that is empty.
  std::size_t checkpoint_every = 0;
  std::filesystem::path checkpoint;
  /// Continue from this checkpoint: it must fingerprint-match the scene (same model, Δt,
  /// integrator, probes); only when the run stops (end_time, max_steps, steady) and the VTU output
  /// may differ. The restored probe history continues, so probes.csv ends as an uninterrupted
  /// run's.
  std::filesystem::path restart;
  /// Seconds the caller took to read the scene (the lattice of a scene with mirror supports is
  /// generated there), reported with the set-up times; 0 if unknown.
  double scene_seconds = 0;
  /// The ranks the run is split over (core/communicator.hpp); null: one process. Every rank
  /// calls run_scene with the same scene and options; rank 0 writes probes.csv, summary.json and
  /// the .pvtu files, every rank its VTU piece and its checkpoint file.
  const Communicator* communicator = nullptr;
  PartitionMethod partition = PartitionMethod::rcb;
};

} // namespace pd
