#include "attitude_propagator/time/stamp_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

namespace {

// Stamps are never trusted to better than this fraction of a period: an ideal simulated clock
// has zero residuals, and round-off must not look like an outlier there.
constexpr double kJitterFloor = 1e-3;
// More lost periods than this between two stamps is no longer a drop but a restart.
constexpr double kMaxSkip = 1e6;
// The lower envelope is the least receipt stamp less the line over the current block of this
// many latency draws and the block before: it forgets what is older than two blocks (a line
// still learning, a spread gone), and the least of 100 to 200 draws lies within a hundredth of
// the spread of its floor when the latency's density there is of the order of 1 / spread.
constexpr std::uint64_t kEnvelopeDraws = 100;

}  // namespace

StampFilter stampFilterFromName(const std::string& name) {
  if (name == "none") return StampFilter::None;
  if (name == "sensor_clock") return StampFilter::SensorClock;
  throw std::invalid_argument("stamp_filter: unknown value '" + logText(name) +
                              "'; accepted: none sensor_clock");
}

std::string stampFilterName(StampFilter filter) {
  return filter == StampFilter::SensorClock ? "sensor_clock" : "none";
}

SensorClockFilter::SensorClockFilter(const Options& options)
    : options_(options), forget_(1.0 - 1.0 / options.memory) {
  if (!(options.memory > 1.0) || !(options.reject_sigmas > 0.0) || options.restart_after < 1 ||
      !(options.restart_jump > 0.0)) {
    throw std::invalid_argument(
        "SensorClockFilter: memory > 1, reject_sigmas > 0, "
        "restart_after >= 1 and restart_jump > 0 required");
  }
}

void SensorClockFilter::reset() {
  samples_ = 0;
  slope_ = 0.0;
  recent_count_ = 0;
  have_previous_ = false;
  exact_interval_ = previous_interval_ = 0.0;
  run_ = 0;
  batch_ = 1;
  run_repeats_ = repeated_ = unfiltered_ = misfit_ = false;
}

double SensorClockFilter::jitter() const { return std::sqrt(variance_); }

double SensorClockFilter::after(double t) {
  // At least kMinStampStep: a published stamp has whole nanoseconds, and two returned stamps
  // closer than that would be published alike (a sample stamped like the one before it). Two
  // nanoseconds, because core time (seconds since the origin, within kFarFromOrigin) carries a
  // round-off of a fraction of one. It also keeps the step off the denormals next to the origin
  // (core time 0 on a whole second), a step cf4 cannot take.
  return std::max(std::nextafter(t, std::numeric_limits<double>::infinity()), t + kMinStampStep);
}

double SensorClockFilter::lineMinus(std::uint64_t index, double t) const {
  // base_t_ - t is exact for nearby stamps; the line's part is relative to base_t_.
  return (base_t_ - t) + (lineRelative(index) + envelope_);
}

namespace {

// Two stamps are "exactly" a period apart when their intervals agree to the round-off of the
// stamps: a few units in the last place of the stamp, and a nanosecond for stamps that were
// integers of nanoseconds.
double spacingTolerance(double t) {
  const double a = std::abs(t);
  return 4.0 * (std::nextafter(a, std::numeric_limits<double>::infinity()) - a) + 1e-9;
}

}  // namespace

SensorClockFilter::Result SensorClockFilter::filter(double t_receipt) {
  const double returned_before = last_output_;
  // A model that did not fit may have learned a wrong period (periods counted wrong): it starts
  // afresh every memory's length of samples, so that a stream that fits again is learned anew.
  if (misfit_ && static_cast<double>(samples_) >= options_.memory) samples_ = 0;
  Result result = model(t_receipt);
  judgeFit();
  if (misfit_) {
    // The receipt stamp as it came, unless it does not follow the last one returned by
    // kMinStampStep (a burst a nanosecond apart; the first receipt stamps after the line's):
    // returned stamps still increase, so no sample is dropped as stale for it.
    last_output_ = std::max(t_receipt, after(returned_before));
    result = {last_output_, Verdict::Unfiltered, result.missed};
  }
  account(result.t, t_receipt);
  return result;
}

// The verdict changes only once the jitter is measured (warm) and a period known; a restart
// keeps it (a stream that does not fit restarts often).
void SensorClockFilter::judgeFit() {
  if (!warm_ || !(slope_ > 0.0)) return;
  const double jitter_periods = jitter() / slope_;
  if (!misfit_ && jitter_periods > kMisfitJitter) {
    misfit_ = true;
    ++fallbacks_;
  } else if (misfit_ && jitter_periods < kFitAgainJitter) {
    misfit_ = false;
  }
}

void SensorClockFilter::account(double t_out, double t_receipt) {
  if (t_out == t_receipt) return;
  ++moved_;
  largest_later_ = std::max(largest_later_, t_out - t_receipt);
  largest_earlier_ = std::max(largest_earlier_, t_receipt - t_out);
}

SensorClockFilter::Result SensorClockFilter::model(double t_receipt) {
  recent_[recent_count_++ % recent_.size()] = t_receipt;
  // FIFO batches, from the stamps alone: a stamp equal to the one before is the same read of
  // the FIFO; a stamp exactly the batch spacing after the one before is the same read too
  // (the driver subtracted whole periods). Anything else starts a new batch.
  const bool repeat = have_previous_ && t_receipt == previous_receipt_;
  bool spaced = false;
  if (repeat) {
    previous_interval_ = 0.0;  // a read of repeated stamps ends at the next stamp, however spaced
  } else if (have_previous_) {
    const double interval = t_receipt - previous_receipt_;
    const double tolerance = spacingTolerance(t_receipt);
    if (interval > 0.0 && std::abs(interval - previous_interval_) <= tolerance) {
      exact_interval_ = interval;
    }
    spaced =
        !run_repeats_ && exact_interval_ > 0.0 && std::abs(interval - exact_interval_) <= tolerance;
    previous_interval_ = interval;
  }
  const bool boundary = !repeat && !spaced;
  if (boundary) {
    if (have_previous_) {
      batch_ = run_;
      repeated_ = run_repeats_;
    }
    run_ = 1;
    run_repeats_ = false;
  } else {
    ++run_;
    run_repeats_ = run_repeats_ || repeat;
  }
  have_previous_ = true;
  previous_receipt_ = t_receipt;

  if (repeat && run_ > static_cast<std::uint64_t>(options_.max_batch)) unfiltered_ = true;
  if (unfiltered_) {
    // Back to the model once a batch of a usable size has been seen whole.
    if (!boundary || batch_ > static_cast<std::uint64_t>(options_.max_batch)) {
      return {t_receipt, Verdict::Unfiltered, 0};
    }
    unfiltered_ = false;
    ++restarts_;
    start(t_receipt);
    return {t_receipt, Verdict::Restarted, 0};
  }
  if (samples_ == 0) {
    start(t_receipt);
    return {t_receipt, Verdict::Restarted, 0};
  }
  if (repeat) return repeated(t_receipt);
  // Since the line's stamp at the newest index; t_receipt - base_t_ is exact, and origin_t_ is
  // kept relative to base_t_ so that epoch-sized stamps lose nothing step after step.
  const double dt = (t_receipt - base_t_) - origin_t_;
  // Index advance: the nearest whole number of periods, at least one (the sensor never repeats
  // an index, so a stamp that arrives early still belongs to the next sample).
  // (Before the period is known, a read of repeated stamps spans as many periods as the read
  // before brought samples.)
  const bool as_batch = boundary && repeated_;
  const double periods = slope_ > 0.0 ? std::round(dt / slope_)
                         : as_batch   ? static_cast<double>(batch_)
                                      : 1.0;
  if (std::abs(dt) > options_.restart_jump + std::max(periods, 1.0) * slope_) {
    ++restarts_;
    start(t_receipt);
    return {t_receipt, Verdict::Restarted, 0};
  }
  // Too many periods for a short time: the period known is far too short (stamps bunched), not
  // a jump of time: the stamps go on from the last one returned.
  if (periods > kMaxSkip) return restartAfter(t_receipt);
  const std::uint64_t m = periods > 1.0 ? static_cast<std::uint64_t>(periods) : 1;
  // After batches of repeated stamps a new stamp is the oldest sample of the next batch, whose
  // newest the stamp belongs to: m periods on is the newest, this sample the one after the
  // last returned. Samples a batch was short of are counted lost here.
  const std::uint64_t short_of = index_ > sample_index_ ? index_ - sample_index_ : 0;
  const std::uint64_t own = index_ + (as_batch ? 1 : m);
  const std::uint64_t lost = as_batch ? short_of : short_of + m - 1;
  const double predicted = static_cast<double>(m) * slope_;
  const double r = dt - predicted;  // innovation
  const double sigma = std::max(jitter(), kJitterFloor * slope_);
  if (boundary) {
    // Warm after warm_up latency draws; or after warm_up samples once a run of exactly spaced
    // stamps longer than max_batch has ended: a clean clock, whose jitter is nil.
    const auto warm_up = static_cast<std::uint64_t>(options_.warm_up);
    warm_ = warm_ || draws_ >= warm_up ||
            (samples_ >= warm_up && batch_ > static_cast<std::uint64_t>(options_.max_batch));
    batch_rejected_ = warm_ && std::abs(r) > options_.reject_sigmas * sigma;
    boundary_as_batch_ = as_batch;
    boundary_missed_ = as_batch || batch_rejected_ ? 0 : lost;
  }
  // A stamp exactly a period after an accepted one shares its latency: it is neither tested
  // nor a new draw of the jitter, but it follows a rejected batch's verdict (and counts
  // towards the restart: a clean clock whose rate changed is one endless batch).
  if (batch_rejected_) {
    ++rejected_;
    if (++rejected_in_a_row_ >= options_.restart_after) return restartAfter(t_receipt);
    // Assume it is the next sample (a late stamp, not a drop) and keep the fit. An early stamp
    // (the rate went up) keeps its own: the line's would run ahead of the samples, and the
    // restart that follows would then have to go back.
    shiftOrigin(1, slope_);
    sample_index_ = index_;
    last_output_ = causal(lowerLine(index_), t_receipt);
    return {last_output_, Verdict::Rejected, 0};
  }
  if (boundary) rejected_in_a_row_ = 0;
  skipped_in_a_row_ = lost > 0 ? skipped_in_a_row_ + 1 : 0;
  if (skipped_in_a_row_ >= options_.restart_after) {  // the rate fell: a new period
    return restartAfter(t_receipt);
  }
  if (slope_ > 0.0 && boundary) {
    // Forgetting average once warm; the plain mean of the first innovations before.
    const double weight = std::max(1.0 - forget_, 1.0 / static_cast<double>(draws_));
    variance_ += weight * (r * r - variance_);
  }
  if (boundary) ++draws_;
  missed_ += lost;
  shiftOrigin(m, predicted);
  add(r);
  refit();
  sample_index_ = own;
  followEnvelope(t_receipt, boundary);
  // The line through noisy stamps can move back by a hair while it learns; stamps must not.
  last_output_ = causal(std::max(lowerLine(sample_index_), last_output_ + 0.5 * slope_), t_receipt);
  return {last_output_, Verdict::Modelled, lost};
}

// A repeated stamp: the next sample of the same batch, at the next index. The batch's stamp
// belongs to its newest sample, so when the batch turns out longer than the periods its stamp
// counted, its point in the fit moves on with the samples. The line's value at the index is
// returned: each sample its own stamp.
SensorClockFilter::Result SensorClockFilter::repeated(double t_receipt) {
  if (run_ == 2 && !boundary_as_batch_) {
    // The batch's first stamp was taken for a single sample after boundary_missed_ lost ones:
    // it was the oldest of this batch. Its stamp stays (already returned); the count is undone.
    missed_ -= boundary_missed_;
    sample_index_ = index_ - boundary_missed_;
    boundary_missed_ = 0;
    skipped_in_a_row_ = 0;
    boundary_as_batch_ = true;
  }
  ++sample_index_;
  if (sample_index_ > index_) {
    if (batch_rejected_) {
      shiftOrigin(sample_index_ - index_, static_cast<double>(sample_index_ - index_) * slope_);
    } else {
      moveNewest(sample_index_ - index_);
    }
  }
  followEnvelope(t_receipt, false);
  last_output_ = causal(lowerLine(sample_index_), t_receipt);
  return {last_output_, Verdict::Modelled, 0};
}

double SensorClockFilter::lineRelative(std::uint64_t index) const {
  return origin_t_ + slope_ * (static_cast<double>(index) - static_cast<double>(index_));
}

double SensorClockFilter::lowerLine(std::uint64_t index) const {
  return base_t_ + (lineRelative(index) + envelope_);
}

// A receipt stamp is the sample's time plus a latency, and a latency is never negative: the
// sample was taken no later than it was received. Least squares put the line through the middle
// of the receipt stamps (the sample's time plus the mean latency), so the line is lowered onto
// their lower envelope, the least receipt stamp less the line (the sample's time plus the least
// latency). The least of n draws of a latency whose density at its floor is f0 lies 1 / (n f0)
// above the floor, where the mean of n draws is off by sigma / sqrt(n): the floor is the better
// known of the two. The constant part of the latency stays in the stamps (no stamp tells it;
// `rate_delay` removes a known one). The envelope is the least over two blocks of
// kEnvelopeDraws draws (the current and the one before, so that it forgets), never above the
// line; a stamp below it lowers it at once. It is learned once warm: before, the line is still
// a guess, and the receipt stamps bound it alone.
void SensorClockFilter::followEnvelope(double t_receipt, bool new_draw) {
  if (!warm_) return;
  if (new_draw && ++block_draws_ > kEnvelopeDraws) {
    previous_block_least_ = block_least_;
    block_least_ = 0.0;
    block_draws_ = 1;
  }
  block_least_ = std::min(block_least_, (t_receipt - base_t_) - lineRelative(sample_index_));
  envelope_ = std::min(block_least_, previous_block_least_);
}

// The one rule for every stamp taken from the line: no later than the receipt stamp it came
// from (the envelope is an estimate; a stamp below it is the better one), and after the stamp
// returned before by kMinStampStep (no stamp published twice). The second wins only where the
// receipt stamps themselves do not advance by kMinStampStep (repeated stamps before a period is
// known, bursts a nanosecond apart).
double SensorClockFilter::causal(double t_line, double t_receipt) const {
  return std::max(std::min(t_line, t_receipt), after(last_output_));
}

// A restart where the stamps went on (a new rate): the new line starts no earlier than the last
// stamp returned, so no sample after it is stale. (A jump restarts at the raw stamp: the
// engine's time policy is to see it.)
SensorClockFilter::Result SensorClockFilter::restartAfter(double t_receipt) {
  ++restarts_;
  const double t = std::max(t_receipt, after(last_output_));
  start(t);
  return {t, Verdict::Restarted, 0};
}

void SensorClockFilter::start(double t_receipt) {
  const double guess = medianRecentInterval();
  s0_ = 1.0;
  sx_ = sxx_ = sy_ = sxy_ = 0.0;
  variance_ = 0.0;
  base_t_ = t_receipt;
  origin_t_ = 0.0;
  slope_ = guess;  // 0 when unknown: the second stamp is then taken as the next sample
  index_ = 0;
  sample_index_ = 0;
  newest_y_ = 0.0;
  envelope_ = block_least_ = previous_block_least_ = 0.0;
  block_draws_ = 1;
  batch_rejected_ = false;
  boundary_as_batch_ = repeated_;
  boundary_missed_ = 0;
  samples_ = 1;
  draws_ = 1;
  warm_ = false;
  rejected_in_a_row_ = 0;
  skipped_in_a_row_ = 0;
  last_output_ = t_receipt;
}

// Moves the origin to index_ + steps at stamp origin_t_ + dt: x -> x - steps, y -> y - dt.
void SensorClockFilter::shiftOrigin(std::uint64_t steps, double dt) {
  const double m = static_cast<double>(steps);
  sxy_ += -m * sy_ - dt * sx_ + m * dt * s0_;
  sxx_ += -2.0 * m * sx_ + m * m * s0_;
  sx_ -= m * s0_;
  sy_ -= dt * s0_;
  index_ += steps;
  origin_t_ += dt;
  newest_y_ -= dt;
}

// The newest point (weight 1, at x = 0) moves `steps` indices on with the origin, its stamp
// unchanged: the points before it move back by as many.
void SensorClockFilter::moveNewest(std::uint64_t steps) {
  const double y = newest_y_;
  const double dt = static_cast<double>(steps) * slope_;
  s0_ -= 1.0;
  sy_ -= y;
  shiftOrigin(steps, dt);
  s0_ += 1.0;
  sy_ += y - dt;
  newest_y_ = y - dt;
  refit();
}

// Older samples lose weight by the forgetting factor; the new one sits at x = 0.
void SensorClockFilter::add(double y) {
  s0_ = forget_ * s0_ + 1.0;
  sx_ *= forget_;
  sxx_ *= forget_;
  sy_ = forget_ * sy_ + y;
  sxy_ *= forget_;
  newest_y_ = y;
  ++samples_;
}

// Weighted least squares y = a + b x; the origin then moves onto the line (a = 0).
void SensorClockFilter::refit() {
  const double det = s0_ * sxx_ - sx_ * sx_;
  // A period is positive: a fit that says otherwise (stamps bunched after a new rate) keeps the
  // period known before; the line's offset still follows the stamps.
  if (det > 1e-12 * s0_ * sxx_) {
    const double slope = (s0_ * sxy_ - sx_ * sy_) / det;
    if (slope > 0.0) slope_ = slope;
  }
  const double a = (sy_ - slope_ * sx_) / s0_;
  sy_ -= a * s0_;
  sxy_ -= a * sx_;
  newest_y_ -= a;
  origin_t_ += a;
}

double SensorClockFilter::medianRecentInterval() const {
  const std::size_t n = std::min(recent_count_, recent_.size());
  if (n < 3) return slope_;
  std::array<double, 6> stamps{};
  for (std::size_t k = 0; k < n; ++k) stamps[k] = recent_[(recent_count_ - n + k) % recent_.size()];
  std::array<double, 5> intervals{};
  for (std::size_t k = 0; k + 1 < n; ++k) intervals[k] = stamps[k + 1] - stamps[k];
  std::sort(intervals.begin(), intervals.begin() + (n - 1));
  const double median = intervals[(n - 1) / 2];
  return median > 0.0 ? median : slope_;
}

RestampCorrection::RestampCorrection(double memory) : forget_(1.0 - 1.0 / memory) {
  if (!(memory > 1.0)) throw std::invalid_argument("RestampCorrection: memory > 1 required");
}

Eigen::Vector3d RestampCorrection::add(const SensorClockFilter& clock,
                                       const SensorClockFilter::Result& sample,
                                       const Eigen::Vector3d& w_B, const Eigen::Quaterniond& q_WB,
                                       bool anchor) {
  if (!started_ || sample.verdict != SensorClockFilter::Verdict::Modelled ||
      clock.index() <= index_) {
    // A new line numbers the samples again, and a rejected stamp is not on the line: the
    // earlier terms stay as last corrected. (So too when a batch's first stamp, taken for one
    // sample, is numbered again as the batch's oldest.)
    start(clock, sample.t, w_B, q_WB, anchor);
    return Eigen::Vector3d::Zero();
  }
  // The origin moves to this sample: x -> x - m, y -> y - d; the newest sample's term, whose
  // rate difference is known now, joins at x = -m, y = -d.
  const double m = static_cast<double>(clock.index() - index_);
  const double d = sample.t - t_;
  sx_ -= m * s0_;
  sy_ -= d * s0_;
  if (count_newest_) {
    const Eigen::Vector3d g = R_WB_ * (w_B - w_B_);
    s0_ += g;
    sx_ -= m * g;
    sy_ -= d * g;
  }
  index_ = clock.index();
  t_ = sample.t;
  w_B_ = w_B;
  R_WB_ = q_WB.toRotationMatrix();
  count_newest_ = true;
  // sum e_n g_n with e_n = t_n - t_n* = y - (t*(index_) - t_) - period x, at today's line.
  const Eigen::Vector3d live = sy_ - clock.lineMinus(index_, t_) * s0_ - clock.period() * sx_;
  const Eigen::Vector3d turn = live - applied_;
  // Forgetting: the fraction 1/memory of every term stays frozen at today's line.
  s0_ *= forget_;
  sx_ *= forget_;
  sy_ *= forget_;
  applied_ = forget_ * live;
  return turn;
}

void RestampCorrection::start(const SensorClockFilter& clock, double t, const Eigen::Vector3d& w_B,
                              const Eigen::Quaterniond& q_WB, bool anchor) {
  started_ = true;
  count_newest_ = !anchor;
  index_ = clock.index();
  t_ = t;
  w_B_ = w_B;
  R_WB_ = q_WB.toRotationMatrix();
  s0_.setZero();
  sx_.setZero();
  sy_.setZero();
  applied_.setZero();
}

}  // namespace attitude_propagator
