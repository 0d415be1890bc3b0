// pd bench --lammps: one LAMMPS run, parsed from its screen output.
#include "lammps.hpp"

#include "libpd/core/child_process.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <string_view>

namespace pd::cli {

std::string lammps_var_error(const std::string& var) {
  const auto eq = var.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == var.size()) {
    return "expected NAME=VALUE";
  }
  const auto is_name = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  };
  const auto is_value = [&](char c) { return is_name(c) || c == '.' || c == '+' || c == '-'; };
  if (!std::all_of(var.begin(), var.begin() + static_cast<std::ptrdiff_t>(eq), is_name) ||
      !std::all_of(var.begin() + static_cast<std::ptrdiff_t>(eq) + 1, var.end(), is_value)) {
    return "NAME may hold letters, digits and _, VALUE also . + -";
  }
  return {};
}

std::optional<LammpsRun> run_lammps(const std::string& lmp, const std::string& input,
                                    std::size_t steps, const std::vector<std::string>& vars) {
  std::string extra;
  for (const auto& v : vars) {
    const auto eq = v.find('=');
    extra += fmt::format(" -var {} {}", v.substr(0, eq), v.substr(eq + 1));
  }
  const std::string cmd = fmt::format("OMP_NUM_THREADS=1 '{}' -in '{}' -log none -echo none "
                                      "-nocite -var steps {}{} 2>&1",
                                      lmp, input, steps, extra);
  LammpsRun r;
  const int status = run_shell_command(cmd, [&r](std::string_view l) {
    // "Loop time of 5.603 on 1 procs for 600 steps with 5229 atoms"
    if (l.starts_with("Loop time of ")) {
      r.loop_seconds = std::strtod(std::string(l.substr(13)).c_str(), nullptr);
    }
    // "Peridynamic bonds: ... total # of bonds = 639066" counts each bond from both ends.
    if (const auto at = l.find("total # of bonds = "); at != std::string_view::npos) {
      r.bonds = std::strtoull(std::string(l.substr(at + 19)).c_str(), nullptr, 10) / 2;
    }
  });
  if (status != 0 || r.loop_seconds <= 0 || r.bonds == 0) {
    return std::nullopt;
  }
  return r;
}

} // namespace pd::cli
