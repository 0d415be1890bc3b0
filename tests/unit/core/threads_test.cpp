// The default thread count follows the processors that other programs leave idle
// (core/threads.hpp): other programs' runnable threads count, this program's own do not.
#include "libpd/core/threads.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace {

TEST(Threads, RunnableCountOfALoadavgLine) {
  EXPECT_EQ(pd::runnable_threads_in_loadavg("0.52 0.58 0.59 3/81 12345"), 3);
  EXPECT_EQ(pd::runnable_threads_in_loadavg("1.00 2.00 3.00 17/1024 99"), 17);
  EXPECT_EQ(pd::runnable_threads_in_loadavg("0.52 0.58 0.59"), -1);
  EXPECT_EQ(pd::runnable_threads_in_loadavg("0.52 0.58 0.59 x/81 1"), -1);
  EXPECT_EQ(pd::runnable_threads_in_loadavg("0.52 0.58 0.59 3"), -1);
}

TEST(Threads, IdleProcessorsAreAtLeastOne) {
  EXPECT_EQ(pd::idle_processors(2, 0), 2);
  EXPECT_EQ(pd::idle_processors(8, 3), 5);
  EXPECT_EQ(pd::idle_processors(2, 2), 1);
  EXPECT_EQ(pd::idle_processors(2, 7), 1);
}

TEST(Threads, OwnBusyThreadsAreNotOthers) {
  std::atomic<bool> stop{false};
  std::thread spinner([&stop] {
    while (!stop.load(std::memory_order_relaxed)) {
    }
  });
  const int with_own = pd::other_runnable_threads();
  stop = true;
  spinner.join();
  ASSERT_GE(with_own, 0) << "/proc/loadavg or /proc/self/task unreadable";
  // Another program's busy process counts (this machine's other load can only add to it).
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    volatile unsigned long turns = 0;
    for (;;) {
      turns = turns + 1;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const int with_child = pd::other_runnable_threads();
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  EXPECT_GE(with_child, 1);
}

TEST(Threads, FollowingSetsOpenMpAndCanBeTurnedOff) {
#ifdef _OPENMP
  const int before = omp_get_max_threads();
  pd::follow_idle_processors(true);
  EXPECT_TRUE(pd::following_idle_processors());
  EXPECT_GE(omp_get_max_threads(), 1);
  EXPECT_LE(omp_get_max_threads(), omp_get_num_procs());
  pd::follow_idle_processors(false);
  omp_set_num_threads(before);
  pd::refresh_thread_count();
  EXPECT_EQ(omp_get_max_threads(), before) << "refresh changed a count the caller set";
#endif
}

} // namespace
