// The subcommands of `pd`, one file each (run.cpp, info.cpp, …): each registers its options on
// the app and returns the action that implements it.
#pragma once

#include "common.hpp"

namespace pd::cli {

Command add_run_command(CLI::App& app);
Command add_info_command(CLI::App& app);
Command add_bench_command(CLI::App& app);
Command add_verify_command(CLI::App& app);
Command add_stability_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_section_command(CLI::App& app);

} // namespace pd::cli
