// The files a run leaves in its output folder: VTU frames with the particles.pvd collection that
// lists them, probes.csv and summary.json. Every file is replaced atomically, so a run that is
// stopped at any point leaves readable files behind.
#pragma once

#include "libpd/app/output_folder.hpp"
#include "libpd/app/probes.hpp"
#include "libpd/app/run_options.hpp"
#include "libpd/core/json.hpp"
#include "libpd/io/scene.hpp"
#include "libpd/time/simulation.hpp"

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace pd {

/// A VTU file written by a run and the time of its state: the entries of particles.pvd.
struct VtuFrame {
  double time = 0;
  std::string file;
};

class RunOutputWriter {
public:
  /// Writes nothing when `folder` is null (no output folder); lists every file it writes in
  /// the folder's manifest.
  RunOutputWriter(OutputFolder* folder, const RunOptions& options, const OutputSpec& output,
                  const std::vector<ResolvedProbe>& probes);

  /// The frames written so far; a checkpoint carries them so that a restarted run's
  /// particles.pvd lists the frames written before the restart too.
  std::vector<VtuFrame>& frames() { return frames_; }
  const std::vector<VtuFrame>& frames() const { return frames_; }

  /// A VTU frame every `vtu_every` steps.
  void frame_if_due(const Simulation& sim);
  /// probes.csv every few seconds, so that an interrupted run keeps what it computed.
  void flush_probes_if_stale(const ProbeHistory& history);
  /// probes.csv as the history stands now (e.g. beside a checkpoint, which it then matches).
  void write_probes(const ProbeHistory& history);
  /// load_curve.csv of a quasi-static fracture run, replaced by `csv`.
  void write_load_curve(const std::string& csv);
  /// The end of a run: the final frame (not of an unstable state), probes.csv without
  /// non-finite rows, and summary.json.
  void write_final(const Simulation& sim, bool unstable, const ProbeHistory& history,
                   const Json& summary);

private:
  void write_frame(const Simulation& sim);
  void write(const std::string& name, const std::string& content);

  OutputFolder* folder_; ///< rank 0's; null on the other ranks
  const Communicator& comm_;
  std::filesystem::path dir_;
  bool vtu_ = false;
  std::size_t vtu_every_ = 0;
  bool history_ = false;
  const std::vector<ResolvedProbe>& probes_;
  std::vector<VtuFrame> frames_;
  std::chrono::steady_clock::time_point last_flush_ = std::chrono::steady_clock::now();
};

} // namespace pd
