#include "libpd/core/blas.hpp"

#include "libpd/core/stop_signals.hpp"

#include <csignal>
#include <cstdlib>
#include <dlfcn.h>
#include <string>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <strings.h>
#include <unistd.h>

namespace pd {

std::string openblas_core() {
  // Looked up at run time: the BLAS is whichever libblas.so.3 the system's alternatives name.
  using CoreName = char* (*)();
  const auto name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  const char* core = name ? name() : nullptr;
  return core ? std::string(core) : std::string();
}

std::string openblas_core_for_this_cpu() {
  if (strcasecmp(openblas_core().c_str(), "prescott") != 0) {
    return {};
  }
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) {
    return "SkylakeX";
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    return "Haswell";
  }
#endif
  return {};
}

namespace {

/// Set on the restart that chose passive waiting, so that the restarted program can take the
/// choice back out of its environment once libgomp has read it.
constexpr const char* passive_marker = "PD_CHOSE_OMP_WAIT_POLICY";

/// Set on the restart to the stop signals the program had unblocked before it (numbers, ','
/// after each): the restart blocks them across exec, and a program that does not take them as
/// requests (pd-fem) must get them back, or SIGTERM and Ctrl-C would never reach it.
constexpr const char* unblock_marker = "PD_STOP_SIGNALS_TO_UNBLOCK";

} // namespace

void take_back_stop_signals_after_restart() {
  const char* list = std::getenv(unblock_marker);
  if (list == nullptr) {
    return;
  }
  sigset_t unblock;
  sigemptyset(&unblock);
  for (const char* p = list; *p != '\0';) {
    char* end = nullptr;
    const long sig = std::strtol(p, &end, 10);
    if (end == p) {
      break;
    }
    for (const int stop : stop_signals) {
      if (sig == stop) {
        sigaddset(&unblock, stop);
      }
    }
    p = *end == ',' ? end + 1 : end;
  }
  unsetenv(unblock_marker);
  sigprocmask(SIG_UNBLOCK, &unblock, nullptr);
}

void restart_with_process_settings(char** argv) {
  take_back_stop_signals_after_restart();
  if (std::getenv(passive_marker) != nullptr) {
    // libgomp has read it: programs pd starts (pd-fem, LAMMPS) see the user's environment.
    unsetenv("OMP_WAIT_POLICY");
    unsetenv(passive_marker);
    return;
  }
  bool changed = false;
  if (std::getenv("OPENBLAS_CORETYPE") == nullptr) {
    const std::string core = openblas_core_for_this_cpu();
    changed = !core.empty() && setenv("OPENBLAS_CORETYPE", core.c_str(), 1) == 0;
  }
  if (std::getenv("OMP_WAIT_POLICY") == nullptr && std::getenv("GOMP_SPINCOUNT") == nullptr &&
      setenv("OMP_WAIT_POLICY", "passive", 1) == 0 && setenv(passive_marker, "1", 1) == 0) {
    changed = true;
  }
  if (changed) {
    // A stop request between here and the restarted program's handlers would kill it (exec
    // resets handlers): blocked, it stays pending across exec until pd takes it as a request.
    const sigset_t stop = stop_signal_set();
    sigset_t before;
    sigprocmask(SIG_BLOCK, &stop, &before);
    std::string unblock;
    for (const int sig : stop_signals) {
      if (sigismember(&before, sig) == 0) {
        unblock += std::to_string(sig) + ',';
      }
    }
    if (!unblock.empty()) {
      setenv(unblock_marker, unblock.c_str(), 1);
    }
    execv("/proc/self/exe", argv);
    unsetenv(unblock_marker);
    sigprocmask(SIG_SETMASK, &before, nullptr);
  }
}

namespace {

// OpenBLAS's own thread count, looked up at run time as openblas_core is (the pthread build
// does not follow OpenMP's).
using GetThreads = int (*)();
using SetThreads = void (*)(int);

GetThreads openblas_get_threads() {
  return reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
}

SetThreads openblas_set_threads() {
  return reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
}

} // namespace

SerialBlas::SerialBlas() {
#ifdef _OPENMP
  openmp_threads_ = omp_get_max_threads();
  omp_set_num_threads(1);
#endif
  const GetThreads get = openblas_get_threads();
  const SetThreads set = openblas_set_threads();
  if (get != nullptr && set != nullptr) {
    openblas_threads_ = get();
    set(1);
  }
}

SerialBlas::~SerialBlas() {
  if (const SetThreads set = openblas_set_threads(); set != nullptr && openblas_threads_ > 0) {
    set(openblas_threads_);
  }
#ifdef _OPENMP
  omp_set_num_threads(openmp_threads_);
#endif
}

} // namespace pd
