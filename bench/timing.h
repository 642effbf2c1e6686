// Per-step cost measured inside one run, so that ratios between methods are trustworthy on a
// noisy, shared machine: one warm-up per method, then several rounds in which every method is
// timed once in turn (a burst of load from another process hits all methods alike), and the
// median over the rounds.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <functional>
#include <vector>

namespace bench {

struct TimingOptions {
  int rounds = 7;             ///< timed chunks per method; the median is reported
  double min_chunk_ms = 3.0;  ///< a chunk repeats the run until it lasts this long
};

/// A callable that performs all steps of one run and returns a value depending on the result
/// (kept in a volatile sink so nothing is optimised away).
using Run = std::function<double()>;

namespace detail {

inline double elapsedNs(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
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
    const auto start = std::chrono::steady_clock::now();
    sink = sink + run();
    const double one_run_ms = detail::elapsedNs(start) * 1e-6;
    runs_per_chunk.push_back(
        std::max(1, static_cast<int>(options.min_chunk_ms / std::max(one_run_ms, 1e-6))));
  }
  std::vector<std::vector<double>> samples(runs.size());
  for (int round = 0; round < options.rounds; ++round) {
    for (std::size_t m = 0; m < runs.size(); ++m) {
      const auto start = std::chrono::steady_clock::now();
      for (int i = 0; i < runs_per_chunk[m]; ++i) sink = sink + runs[m]();
      samples[m].push_back(detail::elapsedNs(start) /
                           (static_cast<double>(runs_per_chunk[m]) * static_cast<double>(steps)));
    }
  }
  std::vector<double> medians;
  for (const auto& s : samples) medians.push_back(detail::median(s));
  return medians;
}

}  // namespace bench
