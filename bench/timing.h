// Per-step cost measured inside one run, so that ratios between methods are trustworthy on a
// noisy, shared machine: one warm-up per method, then several rounds in which every method is
// timed once in turn (a burst of load from another process hits all methods alike), and the
// median over the rounds. The clock is this thread's CPU time, so time spent descheduled while
// other processes run (compilers on a shared 2-core machine) is not counted.
#pragma once

#include <algorithm>
#include <cstddef>
#include <ctime>
#include <functional>
#include <vector>

namespace bench {

struct TimingOptions {
  int rounds = 9;             ///< timed chunks per method; the median is reported
  double min_chunk_ms = 2.0;  ///< a chunk repeats the run until it lasts this long
};

/// A callable that performs all steps of one run and returns a value depending on the result
/// (kept in a volatile sink so nothing is optimised away).
using Run = std::function<double()>;

namespace detail {

/// CPU time of the calling thread, ns.
inline double threadNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

inline double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace detail

/// Median nanoseconds per step of each run (each performs `steps` steps), interleaved.
inline std::vector<double> medianNsPerStep(const std::vector<Run>& runs, std::size_t steps,
                                           const TimingOptions& options = {}) {
  volatile double sink = 0.0;
  std::vector<int> runs_per_chunk;
  for (const Run& run : runs) {
    sink = sink + run();  // warm-up: caches, branch predictors, lazy initialisation
    const double start = detail::threadNs();
    sink = sink + run();
    const double one_run_ms = (detail::threadNs() - start) * 1e-6;
    runs_per_chunk.push_back(
        std::max(1, static_cast<int>(options.min_chunk_ms / std::max(one_run_ms, 1e-6))));
  }
  std::vector<std::vector<double>> samples(runs.size());
  for (int round = 0; round < options.rounds; ++round) {
    for (std::size_t m = 0; m < runs.size(); ++m) {
      const double start = detail::threadNs();
      for (int i = 0; i < runs_per_chunk[m]; ++i) sink = sink + runs[m]();
      const double runs_done = static_cast<double>(runs_per_chunk[m]);
      samples[m].push_back((detail::threadNs() - start) / (runs_done * static_cast<double>(steps)));
    }
  }
  std::vector<double> medians;
  for (const auto& s : samples) medians.push_back(detail::median(s));
  return medians;
}

}  // namespace bench
