// Programs pd starts run with the stop signals as a shell gives them, whatever pd's own mask.
#include "libpd/core/child_process.hpp"
#include "libpd/core/stop_signals.hpp"

#include <csignal>
#include <gtest/gtest.h>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace {

TEST(ChildProcess, AChildCanBeStoppedWhileTheParentBlocksTheStopSignals) {
  // As pd holds them (app/interrupt.hpp). std::system would hand the child this mask: the shell's
  // SIGTERM to itself would wait, blocked, and the child would exit 7.
  const sigset_t stop = pd::stop_signal_set();
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  const int status = pd::run_shell_command("kill -TERM $$; exit 7");
  ASSERT_TRUE(WIFSIGNALED(status)) << "wait status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  const int interrupted = pd::run_shell_command("kill -INT $$; exit 7");
  ASSERT_TRUE(WIFSIGNALED(interrupted)) << "wait status " << interrupted;
  EXPECT_EQ(WTERMSIG(interrupted), SIGINT);
}

TEST(ChildProcess, ExitStatusAndOutputLines) {
  EXPECT_EQ(WEXITSTATUS(pd::run_shell_command("exit 3")), 3);
  std::vector<std::string> lines;
  const int status =
      pd::run_shell_command("printf 'first\\n\\nthird' && echo err >&2",
                            [&lines](std::string_view line) { lines.emplace_back(line); });
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(lines, (std::vector<std::string>{"first", "", "third"}));
}

} // namespace
