// How many threads libpd's parallel loops use when the user fixed none: the processors that no
// other program's runnable thread holds, read again during a run.
//
// Why not all processors: on a shared machine (CI runners, lab workstations) a parallel region
// ends only when its slowest thread does, and a thread that shares its core with another
// program's gets a fraction of it. With a busy process per core, two threads took up to 1.2–1.5×
// the one-thread time on the clamped beam's static solve (many short regions), even with passive
// waiting (core/blas.hpp). Counting the runnable threads the kernel reports is instantaneous
// (the load averages lag by a minute and count this program's own threads), and results do not
// depend on the thread count (bitwise, docs/performance.md), so following the machine changes
// only the time.
#pragma once

#include <string_view>

namespace pd {

/// Runnable threads besides this process's own, from /proc/loadavg's "running/total" field and
/// the running threads of /proc/self/task (one reading); -1 where either cannot be read.
int other_runnable_threads();

/// The parsing behind other_runnable_threads: the runnable count of a /proc/loadavg line
/// ("0.52 0.58 0.59 3/81 12345" → 3), or -1.
int runnable_threads_in_loadavg(std::string_view line);

/// max(1, processors − others): the threads that run without waiting for a core.
int idle_processors(int processors, int others);

/// Makes the OpenMP thread count follow the idle processors (`on`), or leaves it to the caller
/// (the default: a program that links libpd keeps OpenMP's own choice unless it asks). On: a
/// background thread reads other_runnable_threads every 25 ms and keeps the fewest of the last
/// ten readings, so a program that runs for a moment (a shell, the reader at the other end of a
/// pipe) does not take a core from a whole run; refresh_thread_count applies it. Until four
/// readings exist (the first 0.1 s) every processor is used, as OpenMP would.
void follow_idle_processors(bool on);

/// Whether follow_idle_processors is on.
bool following_idle_processors();

/// The OpenMP threads a parallel region started now would use (1 without OpenMP).
int current_thread_count();

/// Sets the OpenMP thread count from the background readings when follow_idle_processors is on
/// (an atomic read otherwise). Loops that run long (time steps, a static solve, benchmark
/// repeats) call it between parallel regions, from the thread that starts them.
void refresh_thread_count();

} // namespace pd
