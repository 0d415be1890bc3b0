// The record of a quasi-static case (rc-beam, compression-cube): one CSV row per increment in
// DIR/curve.csv, rewritten atomically after every increment so that an interrupted run keeps the
// curve so far, and VTU files of the particles after chosen increments.
#pragma once

#include "libpd/core/atomic_file.hpp"
#include "libpd/io/output.hpp"
#include "libpd/time/quasi_static.hpp"

#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace pd::verification {

class CurveRecorder {
public:
  using Row = std::function<std::string(const Simulation&, const quasi_static::IncrementInfo&)>;

  /// `dir` empty: nothing is written. `vtu_increments` are 1-based increment numbers.
  CurveRecorder(std::filesystem::path dir, const std::string& header, std::vector<int> vtu_increments,
                std::string vtu_prefix, Row row)
      : dir_(std::move(dir)), csv_(header + "\n"), vtu_increments_(std::move(vtu_increments)),
        vtu_prefix_(std::move(vtu_prefix)), row_(std::move(row)) {}

  void operator()(const Simulation& sim, const quasi_static::IncrementInfo& info) {
    csv_ += row_(sim, info) + "\n";
    if (dir_.empty()) {
      return;
    }
    write_file_atomically(dir_ / "curve.csv", csv_);
    for (int v : vtu_increments_) {
      if (v == info.index) {
        write_vtu(dir_ / fmt::format("{}-inc{:03d}.vtu", vtu_prefix_, info.index), sim);
      }
    }
  }

private:
  std::filesystem::path dir_;
  std::string csv_;
  std::vector<int> vtu_increments_;
  std::string vtu_prefix_;
  Row row_;
};

} // namespace pd::verification
