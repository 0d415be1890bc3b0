// The files a run leaves in its output folder (VTU frames, particles.pvd, probes.csv,
// summary.json).
#include "libpd/app/run_output.hpp"

#include "libpd/core/atomic_file.hpp"
#include "libpd/io/output.hpp"

#include <fmt/format.h>

namespace pd {

RunOutputWriter::RunOutputWriter(OutputFolder* folder, const RunOptions& options,
                                 const OutputSpec& output, const std::vector<ResolvedProbe>& probes)
    : folder_(folder),
      comm_(options.communicator != nullptr ? *options.communicator : serial_communicator()),
      dir_(folder ? folder->dir() : options.output_dir),
      vtu_(!dir_.empty() && options.write_vtu && output.vtu), vtu_every_(output.vtu_every),
      history_(!dir_.empty() && output.history_every > 0), probes_(probes) {}

void RunOutputWriter::frame_if_due(const Simulation& sim) {
  if (vtu_ && vtu_every_ > 0 && sim.state().step % vtu_every_ == 0) {
    write_frame(sim);
  }
}

void RunOutputWriter::flush_probes_if_stale(const ProbeHistory& history) {
  if (history_ && std::chrono::steady_clock::now() - last_flush_ > std::chrono::seconds(5)) {
    write_probes(history);
  }
}

void RunOutputWriter::write_probes(const ProbeHistory& history) {
  if (!history_) {
    return;
  }
  write("probes.csv", probes_csv(probes_, history));
  last_flush_ = std::chrono::steady_clock::now();
}

void RunOutputWriter::write_load_curve(const std::string& csv) {
  if (!dir_.empty()) {
    write("load_curve.csv", csv);
  }
}

void RunOutputWriter::write_final(const Simulation& sim, bool unstable, const ProbeHistory& history,
                                  const Json& summary) {
  if (dir_.empty()) {
    return;
  }
  if (!unstable && vtu_) {
    write_frame(sim);
  }
  if (history_) {
    write("probes.csv", probes_csv(probes_, history.finite_rows()));
  }
  write("summary.json", summary.dump());
}

void RunOutputWriter::write_frame(const Simulation& sim) {
  const std::string base = fmt::format("particles-{:08d}", sim.state().step);
  std::string name = base + ".vtu";
  if (comm_.size() == 1) {
    folder_->add(dir_ / name);
    write_vtu(dir_ / name, sim);
  } else {
    // One piece per rank, then the .pvtu that joins them once every piece is in place.
    std::vector<std::string> pieces;
    for (int r = 0; r < comm_.size(); ++r) {
      pieces.push_back(fmt::format("{}-r{:04d}.vtu", base, r));
      if (folder_ != nullptr) {
        folder_->add(dir_ / pieces.back());
      }
    }
    comm_.barrier(); // listed before they exist
    write_vtu(dir_ / pieces[static_cast<std::size_t>(comm_.rank())], sim);
    comm_.barrier();
    name = base + ".pvtu";
    if (comm_.root()) {
      write(name, pvtu_text(pieces, !sim.model().state.damage.empty()));
    }
  }
  frames_.push_back({sim.state().time, name});
  if (!comm_.root()) {
    return;
  }
  std::string pvd =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (const auto& [t, f] : frames_) {
    pvd += fmt::format("<DataSet timestep=\"{}\" file=\"{}\"/>\n", t, f);
  }
  pvd += "</Collection>\n</VTKFile>\n";
  write("particles.pvd", pvd);
}

void RunOutputWriter::write(const std::string& name, const std::string& content) {
  if (!comm_.root()) {
    return; // rank 0 writes the run's shared files
  }
  // Listed before it exists: a run killed between the two leaves a manifest naming a file that
  // is missing, never a file that no manifest names.
  folder_->add(dir_ / name);
  write_file_atomically(dir_ / name, content);
}

} // namespace pd
