#include "attitude_propagator/engine.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/publish_grid.h"

namespace attitude_propagator {

namespace {

constexpr Stamp kNsPerSecond = 1000000000;
// Core time is a double of seconds since the origin: its resolution stays below 1e-10 s within
// 1e6 s of it. A gap that lands further away moves the origin to it (see rebaseIfFar).
constexpr double kFarFromOrigin = 1e6;

void checkMaxFuture(double max_future) {
  if (!(max_future >= 0.0 && max_future <= kMaxFuture)) {
    throw std::invalid_argument("max_future: accepted: 0 to " + std::to_string(kMaxFuture) +
                                " s, got " + std::to_string(max_future));
  }
}

/// rate_delay in nanoseconds, or std::invalid_argument: a delay longer than the longest gap
/// integrated across would put every sample behind the one before a gap.
Stamp checkedRateDelay(const EngineConfig& c) {
  const double max_dt = timePolicyOf(c).max_dt;
  if (!(c.rate_delay >= 0.0 && c.rate_delay <= max_dt)) {
    throw std::invalid_argument("rate_delay: accepted: 0 to max_dt = " + std::to_string(max_dt) +
                                " s, got " + std::to_string(c.rate_delay));
  }
  return static_cast<Stamp>(std::llround(c.rate_delay * 1e9));
}

}  // namespace

AttitudeEngine::AttitudeEngine(const EngineConfig& config, EngineSink& sink)
    : config_(config), sink_(sink), propagator_(makePropagator(config_, *this)) {
  if (!(config_.publish_rate > 0.0) || !std::isfinite(config_.publish_rate)) {
    throw std::invalid_argument("publish_rate: must be positive and finite");
  }
  checkMaxFuture(config_.max_future);
  rate_delay_ns_ = checkedRateDelay(config_);
  if (!config_.gyro_bias_B.allFinite() || config_.gyro_bias_B.norm() > kMaxBodyRate) {
    throw std::invalid_argument(
        "gyro_bias: must be finite, each magnitude at most the largest "
        "accepted body rate");
  }
  gyro_bias_B_ = config_.gyro_bias_B;
  // A FIFO read stamps its samples alike; the sensor-clock filter gives each its own stamp.
  const bool fifo_reads = propagator_->takesRepeatedRateStamps();
  for (Source s : {Source::Imu, Source::Twist}) timeline(s).allowRepeatedStamps(fifo_reads);
  default_R_B_ = config_.rate_stddev * config_.rate_stddev * Eigen::Matrix3d::Identity();
  P_B_ = initialCovariance();
}

Eigen::Matrix3d AttitudeEngine::initialCovariance() const {
  const double s = config_.initial_orientation_stddev;
  return clampOrientationCovariance(s * s * Eigen::Matrix3d::Identity());
}

AttitudeEngine::~AttitudeEngine() = default;

// ---------------------------------------------------------------------------------------------
// Time
// ---------------------------------------------------------------------------------------------

double AttitudeEngine::coreTime(Stamp stamp) {
  // Whole seconds keep the publish grid exact in core time.
  if (!origin_) origin_ = stamp - stamp % kNsPerSecond;
  return static_cast<double>(stamp - *origin_) * 1e-9;
}

std::optional<Stamp> AttitudeEngine::stampAt(double t) const {
  if (!origin_) return std::nullopt;
  return *origin_ + static_cast<Stamp>(std::llround(t * 1e9));
}

void AttitudeEngine::rebaseIfFar(Stamp stamp) {
  // After a gap or an anchor the state holds at `stamp` with nothing to integrate from: pinning
  // it there again, with the origin moved to the stamp, loses nothing and keeps core time
  // precise after a jump far ahead (a driver stamping in the year 2100).
  if (std::abs(coreTime(stamp)) < kFarFromOrigin) return;
  const EngineState held = state();
  origin_ = stamp - stamp % kNsPerSecond;
  const double t = coreTime(stamp);
  try {
    propagator_->setState(t, held.q_WB, held.w_B);
  } catch (const std::exception&) {
    resetState(true);  // a held state is always valid; should it not be, start afresh
  }
}

Stamp AttitudeEngine::gridStamp(std::int64_t k) const {
  return attitude_propagator::gridStamp(k, config_.publish_rate);
}

std::int64_t AttitudeEngine::gridIndexAtOrBefore(Stamp now) const {
  return attitude_propagator::gridIndexAtOrBefore(now, config_.publish_rate);
}

bool AttitudeEngine::clockWentBack(Stamp now) {
  const double threshold = timePolicyOf(config_).backward_jump;
  const bool back = clock_ && static_cast<double>(*clock_ - now) * 1e-9 > threshold;
  if (back) {
    // A looped bag or a restarted simulation: the past is gone.
    ++counters_.resets;
    sink_.note({EngineNote::ClockJumpedBack, std::nullopt, now});
    resetState(true);
  }
  return back;
}

void AttitudeEngine::clockTick(Stamp now) {
  if (now <= 0) return;  // sim time before the first /clock
  const bool back = clockWentBack(now);
  const double max_dt = timePolicyOf(config_).max_dt;
  const bool jumped = !back && clock_ && static_cast<double>(now - *clock_) * 1e-9 > max_dt;
  advanceClock(now, back);
  propagator_->publishDue(jumped);
}

void AttitudeEngine::poll(Stamp now) {
  if (now <= 0) return;
  advanceClock(now, clockWentBack(now));
  propagator_->publishDue(false);
}

void AttitudeEngine::drain() { propagator_->publishDue(false); }

bool AttitudeEngine::tooFarAhead(Stamp stamp) const {
  return clock_ && static_cast<double>(stamp - *clock_) * 1e-9 > config_.max_future;
}

void AttitudeEngine::advanceClock(Stamp now, bool went_back) {
  // A step back within the threshold is jitter of the time source: the clock stays put.
  clock_ = went_back || !clock_ ? now : std::max(*clock_, now);
}

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

void AttitudeEngine::reject(Rejection why) {
  ++counters_.received;
  switch (why) {
    case Rejection::NoRate:
      ++counters_.rejected_no_rate;
      break;
    case Rejection::WrongType:
      ++counters_.rejected_type;
      break;
    case Rejection::NoTransform:
      ++counters_.dropped_no_tf;
      break;
    case Rejection::NoTime:
      ++counters_.dropped_no_time;
      break;
    case Rejection::BadCovariance:
      ++counters_.rejected_covariance;
      break;
  }
}

void AttitudeEngine::submit(const Input& raw) {
  ++counters_.received;
  Input input = raw;
  if (input.source != Source::Torque) input.stamp -= rate_delay_ns_;  // the rate's own instant
  if (!input.value.allFinite() || !input.rate_covariance_B.allFinite()) {
    handleOutcome(StampOutcome::RejectedNonFinite, input.source, input.stamp);
    return;
  }
  if (tooFarAhead(input.stamp)) {
    // Published, it would hold every tf listener's transform ahead of its clock, and the
    // inputs that follow would look stale behind it.
    ++counters_.rejected_future;
    sink_.note({EngineNote::Future, input.source, input.stamp});
    return;
  }
  if (!inOrder(input.source, input.stamp)) return;
  // A bias stamped at or before the message's own stamp applies to it.
  if (input.source != Source::Torque) input.value -= biasAt(raw.stamp);
  propagator_->submit(input);
}

bool AttitudeEngine::inOrder(Source source, Stamp stamp) {
  SourceTimeline& line = timeline(source);
  switch (line.judge(stamp, timePolicyOf(config_))) {
    case SourceTimeline::Verdict::InOrder:
      break;
    case SourceTimeline::Verdict::Straggler:
      ++counters_.dropped_stale;
      sink_.note({EngineNote::Stale, source, stamp});
      return false;
    case SourceTimeline::Verdict::JumpedBack:
      restartTimeline(source, stamp);
      break;
  }
  if (clock_) timeline(source).observeLag(*clock_, stamp);
  return true;
}

void AttitudeEngine::restartTimeline(Source source, Stamp stamp) {
  ++counters_.jumps_back;
  sink_.note({EngineNote::StampsJumpedBack, source, stamp});
  if (propagator_->restartInputOrder(source)) {
    // The model's time is the inputs' (kinematic): it starts again with them, from the initial
    // state, and the outputs' stamps start again too.
    ++counters_.resets;
    resetState(true);
    timeline(source).judge(stamp, timePolicyOf(config_));  // forgotten with the rest: the first
  }
}

std::optional<double> AttitudeEngine::inputLag(Source source) const {
  return timelines_[static_cast<std::size_t>(source)].lag();
}

bool AttitudeEngine::submitBias(Stamp stamp, const Eigen::Vector3d& gyro_bias_B) {
  // A bias sample stream should be slow (a calibration): more than this many ahead of the
  // rates means the stamps are wrong; the oldest then takes effect early.
  constexpr std::size_t kMaxPendingBias = 64;
  if (!gyro_bias_B.allFinite() || !(gyro_bias_B.norm() <= kMaxBodyRate)) {
    ++counters_.rejected_bias;
    return false;
  }
  if (pending_gyro_bias_.size() >= kMaxPendingBias) {
    gyro_bias_B_ = pending_gyro_bias_.front().second;
    pending_gyro_bias_.erase(pending_gyro_bias_.begin());
  }
  const auto at = std::upper_bound(
      pending_gyro_bias_.begin(), pending_gyro_bias_.end(), stamp,
      [](Stamp s, const std::pair<Stamp, Eigen::Vector3d>& other) { return s < other.first; });
  pending_gyro_bias_.insert(at, {stamp, gyro_bias_B});
  return true;
}

const Eigen::Vector3d& AttitudeEngine::biasAt(Stamp stamp) {
  std::size_t n = 0;
  while (n < pending_gyro_bias_.size() && pending_gyro_bias_[n].first <= stamp)
    gyro_bias_B_ = pending_gyro_bias_[n++].second;
  pending_gyro_bias_.erase(pending_gyro_bias_.begin(), pending_gyro_bias_.begin() + n);
  return gyro_bias_B_;
}

bool AttitudeEngine::handleOutcome(StampOutcome outcome, std::optional<Source> source,
                                   Stamp stamp) {
  const bool input = source.has_value();
  switch (outcome) {
    case StampOutcome::Anchored:
    case StampOutcome::Advanced:
      if (input) ++counters_.accepted;
      return true;
    case StampOutcome::HeldGap:
      if (input) ++counters_.accepted;
      ++counters_.gaps;
      sink_.note({EngineNote::Gap, source, stamp});
      rebaseIfFar(stamp);
      return true;
    case StampOutcome::Waiting:
      if (input) ++counters_.accepted;
      return false;  // nothing integrated yet: nothing to publish
    case StampOutcome::DroppedStale:
      if (input) ++counters_.dropped_stale;
      if (input) sink_.note({EngineNote::Stale, source, stamp});
      return false;
    case StampOutcome::RejectedNonFinite:
      ++counters_.rejected_non_finite;
      sink_.note({EngineNote::NonFinite, source, stamp});
      return false;
    case StampOutcome::RejectedOutOfRange:
      ++counters_.rejected_out_of_range;
      sink_.note({EngineNote::OutOfRange, source, stamp});
      return false;
    case StampOutcome::FailedStep:
      if (input) ++counters_.accepted;  // it acts from the new anchor
      ++counters_.failed_steps;
      sink_.note({EngineNote::FailedStep, source, stamp});
      return true;  // held and re-anchored at the stamp, like a gap
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// State
// ---------------------------------------------------------------------------------------------

EngineState AttitudeEngine::state() const {
  EngineState s = propagator_->state();
  s.P_B = P_B_;
  return s;
}

EngineState AttitudeEngine::stateAt(Stamp stamp) const {
  EngineState s = state();
  s.stamp = stamp;
  return s;
}

void AttitudeEngine::emitState(Stamp stamp) {
  if (last_published_ && stamp <= *last_published_) return;  // one per stamp
  EngineState s = stateAt(stamp);
  if (!s.q_WB.coeffs().allFinite() || !s.w_B.allFinite()) {
    // The core guarantees finite states; if that ever breaks, never hand NaN on.
    ++counters_.failed_steps;
    ++counters_.resets;
    sink_.note({EngineNote::FailedStep, std::nullopt, stamp});
    resetState(false);
    return;
  }
  last_published_ = stamp;
  sink_.publishState(s);
}

void AttitudeEngine::inputApplied(const Input& input, Stamp stamp) {
  sink_.inputApplied(input, stateAt(stamp));
}

void AttitudeEngine::propagateCovariance(double h, const Eigen::Vector3d& w_step,
                                         const Eigen::Matrix3d& rate_covariance_B) {
  const Eigen::Matrix3d& R_B = rate_covariance_B.isZero(0.0) ? default_R_B_ : rate_covariance_B;
  P_B_ = propagateOrientationCovariance(P_B_, h, w_step, R_B);
}

void AttitudeEngine::resetState(bool forget_time) {
  propagator_->reset();  // queued inputs dropped, counted
  P_B_ = initialCovariance();
  if (forget_time) {
    origin_.reset();
    last_published_.reset();
    for (SourceTimeline& line : timelines_) line.forget();
  }
}

std::string AttitudeEngine::reconfigure(const EngineConfig& next) {
  if (next.model != config_.model) return "model: cannot change while running";
  Stamp rate_delay_ns = 0;
  try {
    checkMaxFuture(next.max_future);
    rate_delay_ns = checkedRateDelay(next);
    propagator_->reconfigure(next);
  } catch (const std::exception& e) {
    return e.what();
  }
  const Eigen::Vector3d bias_B = config_.gyro_bias_B;  // the topic's bias stays in force
  config_ = next;
  config_.gyro_bias_B = bias_B;
  rate_delay_ns_ = rate_delay_ns;
  default_R_B_ = config_.rate_stddev * config_.rate_stddev * Eigen::Matrix3d::Identity();
  return {};  // P_B carries on: the new propagator starts from the current state
}

void AttitudeEngine::reset() {
  ++counters_.resets;
  resetState(false);
}

std::string AttitudeEngine::setState(Stamp stamp, const Eigen::Quaterniond& q_WB,
                                     const Eigen::Vector3d& w_B) {
  if (stamp <= 0) return "no time to pin the state at: give header.stamp";
  if (tooFarAhead(stamp)) {
    return "stamp " + std::to_string(static_cast<double>(stamp - *clock_) * 1e-9) +
           " s ahead of the clock; accepted: at most max_future = " +
           std::to_string(config_.max_future) + " s";
  }
  try {
    propagator_->setState(coreTime(stamp), q_WB, w_B);
  } catch (const std::exception& e) {
    return e.what();
  }
  P_B_.setZero();  // pinned: the state is what the caller says it is
  emitState(stamp);
  return {};
}

}  // namespace attitude_propagator
