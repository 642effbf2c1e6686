// Stamps from a model of the sensor clock instead of the receipt times of the samples.
//
// A driver that stamps samples when they are received adds the transport delay and its
// jitter to every stamp. The sensor itself samples on its own clock: sample n is taken at
// offset + period * n, with period and offset drifting slowly. The filter counts the sensor's
// periods (a stamp about m periods after the last one is m samples later: m - 1 were lost),
// fits the line t(n) by least squares with exponential forgetting, and returns the line at
// the sample's index: the receipt jitter is averaged over the filter's memory.
//
// Causal: a receipt stamp is the sample's time plus a latency >= 0, so the line is lowered onto
// the lower envelope of the receipt stamps (the least latency) and a returned stamp is never
// later than the receipt stamp it came from (docs/numerics.md §3). The constant part of the
// latency stays in the stamps: no stamp tells it (`rate_delay` removes a known one).
//
// A stamp is returned when its sample arrives, from the line known then; the line keeps
// improving afterwards. RestampCorrection carries the later, better stamps of the samples
// already integrated into the orientation, to first order.
//
// FIFO batches (docs/numerics.md §3): a driver that reads several samples at once gives them
// either the same receipt stamp (repeated stamps) or the receipt stamp less k periods for the
// k-th newest (stamps exactly a period apart). Either way a batch is one draw of the latency:
// the filter recognises a batch from the stamps alone, gives every sample its own index, fits
// the batch's stamp once (a repeated stamp belongs to the batch's newest sample) and measures
// the jitter only at batch boundaries.
//
// A stream the model does not fit (its stamps' scatter about the line, jitter(), comparable to
// the period: a whole number of periods can no longer be told from the jitter) gets its receipt
// stamps back until it fits again (misfit(), docs/numerics.md §3).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <Eigen/Geometry>

namespace attitude_propagator {

/// Seconds by which a stamp the filter returns follows the one before, at least: a published
/// stamp has whole nanoseconds, and core time's round-off is a fraction of one, so two returned
/// stamps are never published alike (docs/numerics.md §3).
constexpr double kMinStampStep = 2e-9;

/// The stamps do not fit the sensor-clock model once their jitter (one standard deviation about
/// the line) exceeds this fraction of the period: an interval's error, sqrt(2) jitter, is then
/// above a third of a period, and one interval in six is counted a period wrong.
constexpr double kMisfitJitter = 0.25;
/// A stream that did not fit is modelled again once its jitter is below this fraction of the
/// period (a period counted wrong about once in 60000 intervals); between the two the last
/// verdict holds, so a stream near the bound does not switch back and forth.
constexpr double kFitAgainJitter = 0.1;

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
    int warm_up = 10;            ///< batches (samples, when alone) after a (re)start before a
                                 ///< stamp can be rejected
    int restart_after = 5;       ///< this many rejected stamps (or lost periods) in a row restart
    double restart_jump = 1.0;   ///< s: a stamp this far from the line restarts at once
    /// Repeated stamps: a batch of more than this many leaves too few batches in the memory to
    /// know the period; its stamps are then returned unfiltered (unfiltered()).
    int max_batch = 100;
  };

  enum class Verdict {
    Modelled,  ///< the stamp joined the fit; the lowered line's value at its index is returned
    /// An outlier: the line's value at the next index is returned, or the stamp itself when
    /// earlier (a rate gone up); the fit unchanged.
    Rejected,
    /// The model started again from this stamp, which is returned as it is: after a jump; after
    /// a run of rejections or of lost periods (a new rate), no earlier than the last returned.
    Restarted,
    /// The stamp returned as it came: a batch of repeated stamps too large to model
    /// (Options::max_batch; the model starts again after the first batch of a usable size), or a
    /// stream that does not fit the model (misfit(); the fit goes on, for the stream to fit again).
    Unfiltered,
  };

  struct Result {
    double t = 0.0;  ///< the filtered stamp
    Verdict verdict = Verdict::Restarted;
    std::uint64_t missed = 0;  ///< periods lost before this sample
  };

  SensorClockFilter() : SensorClockFilter(Options{}) {}
  explicit SensorClockFilter(const Options& options);

  /// Feeds a receipt stamp (finite, seconds) and returns the sensor-clock stamp, never later
  /// than t_receipt. The returned stamps increase strictly, by kMinStampStep at least, until a
  /// restart (a jump restarts at the stamp as it came; every other restart no earlier than
  /// kMinStampStep after the last); where the receipt stamps themselves advance by less (repeated
  /// stamps before a period is known), that wins and the stamp follows the last by kMinStampStep.
  Result filter(double t_receipt);

  /// Forgets the model: the next stamp starts it again.
  void reset();

  /// Sensor period (s), 0 before two stamps.
  double period() const { return slope_; }
  /// Stamp of the model's sample index 0 (the first since the last start), on the line lowered
  /// onto the receipt stamps' lower envelope: t(n) = offset + period n.
  double offset() const {
    return base_t_ + (origin_t_ + envelope_ - slope_ * static_cast<double>(index_));
  }
  /// The (lowered) line's stamp of sample `index` (since the last start) minus t: how far the
  /// model now puts that sample from the stamp t it was given, free of the round-off of
  /// epoch-sized stamps.
  double lineMinus(std::uint64_t index, double t) const;
  /// Standard deviation of the stamps about the line (s).
  double jitter() const;
  /// The forgetting memory (samples).
  double memory() const { return options_.memory; }
  std::uint64_t rejected() const { return rejected_; }
  std::uint64_t missed() const { return missed_; }
  std::uint64_t restarts() const { return restarts_; }
  /// The sample index of the stamp last returned (since the last start).
  std::uint64_t index() const { return sample_index_; }
  /// Samples in the last FIFO batch the stamps showed (repeated stamps, or stamps exactly a
  /// period apart); 1 while every sample comes on its own.
  std::uint64_t batchSize() const { return batch_; }
  /// True while batches of repeated stamps are too large to model (Options::max_batch): the
  /// stamps are then returned unfiltered.
  bool unfiltered() const { return unfiltered_; }
  /// True while the stream does not fit the model (jitter() above kMisfitJitter periods, until
  /// below kFitAgainJitter): the receipt stamps are returned as they came (moved on only to
  /// follow the stamp returned before by kMinStampStep).
  bool misfit() const { return misfit_; }
  /// Times the stream stopped fitting the model (each a fall back to the receipt stamps).
  std::uint64_t fallbacks() const { return fallbacks_; }
  /// Samples whose returned stamp differs from their receipt stamp, since construction.
  std::uint64_t moved() const { return moved_; }
  /// The most a returned stamp was later than its receipt stamp (s, >= 0: 0 unless receipt
  /// stamps came less than kMinStampStep apart), and earlier.
  double largestLater() const { return largest_later_; }
  double largestEarlier() const { return largest_earlier_; }

 private:
  void start(double t_receipt);
  Result model(double t_receipt);
  void judgeFit();
  void account(double t_out, double t_receipt);
  Result restartAfter(double t_receipt);
  /// The smallest stamp after t, at least 1 ps later: returned stamps increase strictly.
  static double after(double t);
  void shiftOrigin(std::uint64_t steps, double dt);
  void moveNewest(std::uint64_t steps);
  Result repeated(double t_receipt);
  double lineRelative(std::uint64_t index) const;
  double lowerLine(std::uint64_t index) const;
  void followEnvelope(double t_receipt, bool new_draw);
  double causal(double t_line, double t_receipt) const;
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
  std::uint64_t index_ = 0;         // the newest point of the fit
  std::uint64_t sample_index_ = 0;  // the sample last returned (behind index_ inside a batch)
  double newest_y_ = 0.0;           // y of the newest point, at x = 0 until the origin moves on
  double envelope_ = 0.0;           // the lower envelope of receipt stamp - line (s, <= 0)
  double block_least_ = 0.0;        // its least over the current block of draws (<= 0)
  double previous_block_least_ = 0.0;
  std::uint64_t block_draws_ = 1;
  std::uint64_t samples_ = 0;  // since the last start
  std::uint64_t draws_ = 0;    // latency draws (batches) since the last start
  bool warm_ = false;          // stamps can be rejected
  int rejected_in_a_row_ = 0;
  int skipped_in_a_row_ = 0;
  std::uint64_t rejected_ = 0, missed_ = 0, restarts_ = 0;
  std::array<double, 6> recent_{};  // the last receipt stamps, for a new period after a restart
  std::size_t recent_count_ = 0;
  // FIFO batches: the stamps' own structure, kept across restarts (it belongs to the driver).
  bool have_previous_ = false;
  double previous_receipt_ = 0.0;
  double previous_interval_ = 0.0;
  double exact_interval_ = 0.0;        // the spacing seen twice in a row to round-off (0: none yet)
  std::uint64_t run_ = 0;              // samples of the current batch so far
  std::uint64_t batch_ = 1;            // samples of the last batch completed
  bool run_repeats_ = false;           // the current batch has repeated stamps
  bool repeated_ = false;              // the last batch completed had repeated stamps
  bool boundary_as_batch_ = false;     // the current batch's first stamp was taken as a batch's
  std::uint64_t boundary_missed_ = 0;  // periods it counted as lost otherwise
  bool batch_rejected_ = false;        // the current batch's first stamp was rejected
  bool unfiltered_ = false;
  bool misfit_ = false;  // kept across restarts (it belongs to the stream); reset() forgets it
  std::uint64_t fallbacks_ = 0, moved_ = 0;
  double largest_later_ = 0.0, largest_earlier_ = 0.0;
};

/// First-order correction of the orientation for stamps the clock model moved after they were
/// integrated. A sample n integrated at t_n instead of its sensor-clock stamp t_n* leaves the
/// world-frame orientation error  -sum_n (t_n - t_n*) R_WB(t_n) (w_{n+1} - w_n)  (the error of
/// sum_n w_n dt_n against the truth at the newest stamp, summed by parts). The clock model's
/// line gives t_n* (SensorClockFilter::lineMinus); every new sample and every move of the line
/// changes the estimate, and the change is returned to be applied. The line of the moment
/// keeps being used for a sample with the filter's forgetting factor: each term's weight is
/// handed over, a fraction 1/memory per sample, to a frozen part at the line of that step,
/// so a drifting clock never re-stamps far into the past. O(1) time and memory per sample.
class RestampCorrection {
 public:
  explicit RestampCorrection(double memory);

  /// Takes the sample just integrated: the clock's answer for it, its body rate and the
  /// orientation it reached. `anchor`: the state's time is defined at this sample's stamp
  /// (its own stamp is never corrected). Returns the world-frame rotation vector v by which
  /// the orientation is to be turned now, q_WB <- Exp(v) q_WB.
  Eigen::Vector3d add(const SensorClockFilter& clock, const SensorClockFilter::Result& sample,
                      const Eigen::Vector3d& w_B, const Eigen::Quaterniond& q_WB, bool anchor);

  /// Forgets the samples: the next one starts a new history.
  void reset() { started_ = false; }

 private:
  void start(const SensorClockFilter& clock, double t, const Eigen::Vector3d& w_B,
             const Eigen::Quaterniond& q_WB, bool anchor);

  double forget_;
  bool started_ = false;
  bool count_newest_ = false;  // the newest sample's term is to be added with the next sample
  // The newest sample: the origin of the sums.
  std::uint64_t index_ = 0;
  double t_ = 0.0;
  Eigen::Vector3d w_B_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_WB_ = Eigen::Matrix3d::Identity();
  // Weighted sums over the terms still re-stamped of g_n = R_WB(t_n) (w_{n+1} - w_n), x g_n and
  // y g_n, x = n - index_, y = t_n - t_ (the origin moves with every sample, as in the filter).
  Eigen::Vector3d s0_ = Eigen::Vector3d::Zero(), sx_ = Eigen::Vector3d::Zero(),
                  sy_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d applied_ = Eigen::Vector3d::Zero();  // the live sums' correction applied so far
};

}  // namespace attitude_propagator
