// Stamps from a model of the sensor clock instead of the receipt times of the samples.
//
// A driver that stamps samples when they are received adds the transport delay and its
// jitter to every stamp. The sensor itself samples on its own clock: sample n is taken at
// offset + period * n, with period and offset drifting slowly. The filter counts the sensor's
// periods (a stamp about m periods after the last one is m samples later: m - 1 were lost),
// fits the line t(n) by least squares with exponential forgetting, and returns the line at
// the sample's index: the receipt jitter is averaged over the filter's memory.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace attitude_propagator {

/// The `stamp_filter` parameter.
enum class StampFilter {
  None,         ///< stamps used as they come
  SensorClock,  ///< SensorClockFilter
};

/// Parses a `stamp_filter` value; throws std::invalid_argument naming the accepted values.
StampFilter stampFilterFromName(const std::string& name);
std::string stampFilterName(StampFilter filter);

class SensorClockFilter {
 public:
  struct Options {
    double memory = 1000.0;      ///< samples: forgetting factor 1 - 1/memory
    double reject_sigmas = 6.0;  ///< a stamp further than this many sigma from the line is rejected
    int warm_up = 10;            ///< samples after a (re)start before stamps can be rejected
    int restart_after = 5;       ///< this many rejected stamps (or lost periods) in a row restart
    double restart_jump = 1.0;   ///< s: a stamp this far from the line restarts at once
  };

  enum class Verdict {
    Modelled,   ///< the stamp joined the fit; the line's value at its index is returned
    Rejected,   ///< an outlier: the line's value at the next index is returned, fit unchanged
    Restarted,  ///< the model started again from this stamp, which is returned as it is
  };

  struct Result {
    double t = 0.0;           ///< the filtered stamp
    Verdict verdict = Verdict::Restarted;
    std::uint64_t missed = 0;  ///< periods lost before this sample
  };

  SensorClockFilter() : SensorClockFilter(Options{}) {}
  explicit SensorClockFilter(const Options& options);

  /// Feeds a receipt stamp (finite, seconds) and returns the sensor-clock stamp. The returned
  /// stamps increase strictly until a restart.
  Result filter(double t_receipt);

  /// Forgets the model: the next stamp starts it again.
  void reset();

  /// Sensor period (s), 0 before two stamps.
  double period() const { return slope_; }
  /// Stamp of the model's sample index 0 (the first since the last start): t(n) = offset + period n.
  double offset() const { return base_t_ + (origin_t_ - slope_ * static_cast<double>(index_)); }
  /// Standard deviation of the stamps about the line (s).
  double jitter() const;
  std::uint64_t rejected() const { return rejected_; }
  std::uint64_t missed() const { return missed_; }
  std::uint64_t restarts() const { return restarts_; }
  std::uint64_t index() const { return index_; }

 private:
  void start(double t_receipt);
  void shiftOrigin(std::uint64_t steps, double dt);
  void add(double y);
  void refit();
  double medianRecentInterval() const;

  Options options_;
  double forget_;
  // Weighted sums over past samples of x = n - index_ and y = t - origin_t_ (the newest index and
  // the line's stamp there are the origin, so every sum stays of the memory's size).
  double s0_ = 0.0, sx_ = 0.0, sxx_ = 0.0, sy_ = 0.0, sxy_ = 0.0;
  double variance_ = 0.0;  // of accepted innovations, s^2
  double base_t_ = 0.0;    // the receipt stamp the model started from
  double origin_t_ = 0.0;  // the line's stamp at index_, relative to base_t_
  double slope_ = 0.0;
  double last_output_ = 0.0;
  std::uint64_t index_ = 0;
  std::uint64_t samples_ = 0;  // since the last start
  int rejected_in_a_row_ = 0;
  int skipped_in_a_row_ = 0;
  std::uint64_t rejected_ = 0, missed_ = 0, restarts_ = 0;
  std::array<double, 6> recent_{};  // the last receipt stamps, for a new period after a restart
  std::size_t recent_count_ = 0;
};

}  // namespace attitude_propagator
