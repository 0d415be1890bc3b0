// Children started with the stop signals as a shell would give them (core/child_process.hpp).
#include "libpd/core/child_process.hpp"

#include "libpd/core/stop_signals.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace pd {

namespace {

std::atomic<pid_t> child{0};

/// Spawns /bin/sh -c `command`, its standard output onto `stdout_fd` when that is not −1.
pid_t spawn_shell(const std::string& command, int stdout_fd, int close_fd) {
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none;
  sigemptyset(&none);
  const sigset_t stop = stop_signal_set();
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &stop);
  // A process group of its own, so that stopping it reaches what the shell starts too.
  posix_spawnattr_setpgroup(&attr, 0);
  posix_spawnattr_setflags(&attr,
                           POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdout_fd != -1) {
    posix_spawn_file_actions_adddup2(&actions, stdout_fd, STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, stdout_fd);
    posix_spawn_file_actions_addclose(&actions, close_fd);
  }
  const char* argv[] = {"sh", "-c", command.c_str(), nullptr};
  pid_t pid = -1;
  const int error =
      posix_spawn(&pid, "/bin/sh", &actions, &attr, const_cast<char**>(argv), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (error != 0) {
    return -1;
  }
  child = pid;
  return pid;
}

int wait_for(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) == -1) {
    if (errno != EINTR) {
      status = -1;
      break;
    }
  }
  child = 0;
  return status;
}

} // namespace

int running_child() {
  return child.load();
}

int run_shell_command(const std::string& command) {
  const pid_t pid = spawn_shell(command, -1, -1);
  return pid == -1 ? -1 : wait_for(pid);
}

int run_shell_command(const std::string& command,
                      const std::function<void(std::string_view line)>& line) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) {
    return -1;
  }
  const pid_t pid = spawn_shell(command, ends[1], ends[0]);
  ::close(ends[1]);
  if (pid == -1) {
    ::close(ends[0]);
    return -1;
  }
  FILE* out = ::fdopen(ends[0], "r");
  if (out == nullptr) {
    ::close(ends[0]);
    return wait_for(pid);
  }
  std::string text;
  for (int c = std::fgetc(out); c != EOF; c = std::fgetc(out)) {
    if (c == '\n') {
      line(text);
      text.clear();
    } else {
      text.push_back(static_cast<char>(c));
    }
  }
  if (!text.empty()) {
    line(text);
  }
  std::fclose(out);
  return wait_for(pid);
}

} // namespace pd
