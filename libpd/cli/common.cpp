// What the subcommands of `pd` share.
#include "common.hpp"

#include <cstdio>
#include <fmt/format.h>
#include <fstream>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace pd::cli {

void set_threads(int threads) {
#ifdef _OPENMP
  if (threads > 0) {
    omp_set_num_threads(threads);
  }
#else
  (void)threads;
#endif
}

int thread_count() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void add_threads_option(CLI::App& command, int& threads) {
  command.add_option("--threads", threads, "OpenMP threads (default: all)");
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  if (!(in >> a >> b >> c)) {
    return "unknown";
  }
  return a + " " + b + " " + c;
}

Scene load_or_explain(const std::string& path) {
  Scene scene = load_scene(path);
  for (const auto& w : scene.warnings) {
    fmt::print(stderr, "{}\n", w);
  }
  return scene;
}

} // namespace pd::cli
