// Programs pd starts (pd-fem for `pd verify`, LAMMPS for `pd bench --lammps`). pd keeps the stop
// signals blocked in every thread and takes them on one thread of its own (app/interrupt.hpp); a
// child started with std::system or popen would inherit that mask and could then not be stopped
// by SIGTERM or Ctrl-C at all. These start the child with the stop signals unblocked and at their
// default action, as from a shell.
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace pd {

/// Runs `command` with /bin/sh -c, waits for it and returns its wait status (as std::system:
/// WIFEXITED / WEXITSTATUS apply); −1 if it could not be started.
int run_shell_command(const std::string& command);

/// As run_shell_command, calling `line` with each line the command writes to its standard output
/// (without the line break).
int run_shell_command(const std::string& command,
                      const std::function<void(std::string_view line)>& line);

/// The child a run_shell_command of this process is waiting for, 0 if none. It leads a process
/// group of its own (kill(−pid, …) reaches what it started): a process that is abandoned on a
/// stop request (app/interrupt.hpp) stops it rather than leave it running alone. A terminal's
/// Ctrl-C reaches pd only, which then stops the child.
int running_child();

} // namespace pd
