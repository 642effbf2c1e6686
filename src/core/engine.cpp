#include "attitude_propagator/engine.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "attitude_propagator/estimation/gravity_direction.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/sample_door.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/time/one_state_per_stamp.h"
#include "attitude_propagator/time/publish_grid.h"

namespace attitude_propagator {

namespace {

/// A fix's covariance: like a rate covariance from a message (finite, symmetric, variances at
/// least 0, correlations at most one), with variances at most pi^2 (an orientation's ceiling).
bool validFixCovariance(const Eigen::Matrix3d& R) {
  return checkRateCovariance(R) == RateCovarianceCheck::Ok &&
         R.diagonal().maxCoeff() <= kMaxOrientationVariance;
}

}  // namespace

AttitudeEngine::AttitudeEngine(const EngineConfig& config, EngineSink& sink)
    : AttitudeEngine(config, sink, makePropagator) {}

AttitudeEngine::AttitudeEngine(const EngineConfig& config, EngineSink& sink,
                               const PropagatorFactory& make)
    : config_(config),
      sink_(sink),
      propagator_(make(config_, time_)),
      replay_(config_.fixes, time_, *propagator_, error_, *this) {
  checkEngineConfig(config_);
  rate_delay_ns_ = rateDelayNs(config_);
  gyro_bias_B_ = config_.gyro_bias_B;
  // A FIFO read stamps its samples alike; the sensor-clock filter gives each its own stamp.
  const bool fifo_reads = propagator_->takesRepeatedRateStamps();
  for (Source s : {Source::Imu, Source::Twist}) {
    order_rule_.timeline(static_cast<std::size_t>(s)).allowRepeatedStamps(fifo_reads);
  }
  default_R_B_ = defaultRateCovariance(config_);
  // The field comes on a topic of its own, stamped between the rates: applied at its stamp.
  keep_history_ = config_.aiding.use_mag;
  tilt_known_ = !config_.aiding.align;
  error_.P_B = initialCovariance();
  resetBiasState();
}

void AttitudeEngine::resetBiasState() {
  const double s = config_.fixes.estimate_gyro_bias ? config_.fixes.gyro_bias_stddev : 0.0;
  error_.bias_B.setZero();
  error_.P_bb = s * s * Eigen::Matrix3d::Identity();
  error_.P_Bb.setZero();
}

Eigen::Vector3d AttitudeEngine::gyroBiasStddev() const {
  if (!config_.fixes.estimate_gyro_bias) return Eigen::Vector3d::Zero();
  return error_.P_bb.diagonal().cwiseMax(0.0).cwiseSqrt();
}

void AttitudeEngine::anchorCovariance() {
  error_.P_B = initialCovariance();
  error_.P_Bb.setZero();  // the initial attitude's error owes nothing to the bias
}

Eigen::Matrix3d AttitudeEngine::initialCovariance() const {
  // Aligned from gravity: nothing is known before the first sample.
  if (config_.aiding.align) return kMaxOrientationVariance * Eigen::Matrix3d::Identity();
  const double s = config_.initial_orientation_stddev;
  return clampOrientationCovariance(s * s * Eigen::Matrix3d::Identity());
}

AttitudeEngine::~AttitudeEngine() = default;

// ---------------------------------------------------------------------------------------------
// Time
// ---------------------------------------------------------------------------------------------

void AttitudeEngine::rebaseIfFar(Stamp stamp) {
  // After a gap or an anchor the state holds at `stamp` with nothing to integrate from: pinning
  // it there again, with the origin moved to the stamp, loses nothing and keeps core time
  // precise after a jump far ahead (a driver stamping in the year 2100).
  if (!time_.isFar(stamp)) return;
  const EngineState held = state();
  replay_.clear();  // its stamps are in core time from the old origin
  time_.rebase(stamp);
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

ClockTimeline::Verdict AttitudeEngine::judgeClock(Stamp now) {
  const ClockTimeline::Verdict verdict = clock_line_.judge(now, timePolicyOf(config_));
  clock_ = clock_line_.now();  // before the notes: the sink may ask what time it is
  switch (verdict) {
    case ClockTimeline::Verdict::JumpedBack:
      // A looped bag or a restarted simulation: the past is gone.
      ++counters_.resets;
      sink_.note({EngineNote::ClockJumpedBack, std::nullopt, now});
      resetState(true);
      break;
    case ClockTimeline::Verdict::TwoTimelines:
      // Two clocks take turns: following either costs nothing more than the jump back before.
      ++counters_.clock_conflicts;
      sink_.note({EngineNote::ClockTwoTimelines, std::nullopt, *clock_line_.other()});
      break;
    case ClockTimeline::Verdict::On:
    case ClockTimeline::Verdict::Ahead:
    case ClockTimeline::Verdict::OtherTimeline:
      break;
  }
  return verdict;
}

void AttitudeEngine::clockTick(Stamp now) {
  if (now <= 0) return;  // sim time before the first /clock
  const ClockTimeline::Verdict verdict = judgeClock(now);
  if (verdict == ClockTimeline::Verdict::OtherTimeline) return;  // not the clock followed
  const bool jumped =
      verdict == ClockTimeline::Verdict::Ahead || verdict == ClockTimeline::Verdict::TwoTimelines;
  publishDue(jumped);
}

void AttitudeEngine::poll(Stamp now) {
  if (now <= 0) return;
  if (judgeClock(now) == ClockTimeline::Verdict::OtherTimeline) return;
  publishDue(false);
}

void AttitudeEngine::drain() { publishDue(false); }

void AttitudeEngine::publishDue(bool skip_intermediate) {
  if (clock_) {
    // A model that publishes from the clock alone (dynamic: on its grid) starts core time there
    // when no input has.
    if (!time_.pinned()) {
      if (const std::optional<Stamp> first = propagator_->firstStampFromClock(*clock_)) {
        time_.pin(*first);
      }
    }
    propagator_->beginDue(*clock_, last_published_, skip_intermediate);
    while (const std::optional<ModelResult> due = propagator_->nextDue(last_published_)) {
      act(*due, nullptr);
    }
  }
  if (keep_history_) applyDueFixes();  // the dynamic model's time moved on
}

bool AttitudeEngine::tooFarAhead(Stamp stamp) const {
  return clock_ && static_cast<double>(stamp - *clock_) * 1e-9 > config_.max_future;
}

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

void AttitudeEngine::reject(Rejection why) {
  ++counters_.received;
  ++(counters_.*rejectionCounter(why));
}

void AttitudeEngine::submit(const Input& raw) {
  ++counters_.received;
  Input input = raw;
  if (input.source != Source::Torque) input.stamp -= rate_delay_ns_;  // the rate's own instant
  // The door (sample_door.h) before the source's order: a refused value never counts as the
  // source's newest, which would make the next on-time inputs stragglers.
  std::optional<StampOutcome> refused =
      refusedValue(input.value, doorBound(input.source == Source::Torque));
  if (!input.rate_covariance_B.allFinite()) refused = StampOutcome::RejectedNonFinite;
  if (refused) {
    countOutcome(*refused, input.source, input.stamp);
    return;
  }
  if (tooFarAhead(input.stamp)) {
    // Published, it would hold every tf listener's transform ahead of its clock, and the
    // inputs that follow would look stale behind it.
    ++counters_.rejected_future;
    sink_.note({EngineNote::Future, input.source, input.stamp});
    return;
  }
  std::vector<ReceivedInput> confirming;
  const ReceivedInput received{input, raw.stamp};
  if (!inOrder(received, confirming)) return;
  // The inputs that confirmed a jump back go first, from the new anchor: the state after the
  // jump is the one a fresh start on the new stamps has.
  for (const ReceivedInput& earlier : confirming) use(earlier);
  use(received);
}

void AttitudeEngine::use(const ReceivedInput& received) {
  Input input = received.input;
  // A bias stamped at or before the message's own stamp applies to it.
  if (input.source != Source::Torque) input.value -= biasAt(received.received_stamp);
  time_.pin(input.stamp);  // the first input the model takes starts core time
  submitToModel(input);
  if (input.source == Source::Imu) last_imu_stamp_ = received.received_stamp;
  if (keep_history_) applyDueFixes();
}

void AttitudeEngine::submitToModel(const Input& input) {
  if (!replay_.takesBiasEstimate(input)) {
    act(propagator_->submit(input, clock_), &input);
    return;
  }
  Input corrected = input;
  corrected.value -= error_.bias_B;
  // The history keeps the input as received: a replay subtracts the estimate as it is then.
  act(propagator_->submit(corrected, clock_), &input);
}

void AttitudeEngine::act(const ModelResult& result, const Input* received) {
  counters_.late += result.late;
  counters_.pending_overflow += result.pending_overflow;
  counters_.deferred_ticks += result.deferred_ticks;
  if (result.note) sink_.note(*result.note);
  if (result.outcome) countOutcome(*result.outcome, result.source, result.stamp);
  followCovariance(result);
  if (result.publish) emitState(result.stamp);
  if (result.hand_on) handOn(*result.input, result.stamp, result.at);
  if (result.keep_step) keepStep(result, received);
}

void AttitudeEngine::keepStep(const ModelResult& result, const Input* received) {
  if (!keep_history_) return;
  if (received != nullptr || result.input != nullptr) {
    replay_.record(ModelStep{received != nullptr ? *received : *result.input, false});
    return;
  }
  Input grid;  // the advance to a grid stamp
  grid.stamp = result.stamp;
  replay_.record(ModelStep{grid, true});
}

namespace {
/// The index of a source in the input order (InputOrder numbers its sources from 0).
std::size_t sourceIndex(Source source) { return static_cast<std::size_t>(source); }
}  // namespace

bool AttitudeEngine::inOrder(const ReceivedInput& received,
                             std::vector<ReceivedInput>& confirming) {
  const Source source = received.input.source;
  const Stamp stamp = received.input.stamp;
  InputOrder<ReceivedInput>::Judged judged =
      order_rule_.judge(sourceIndex(source), stamp, received, clock_, timePolicyOf(config_));
  for (const ReceivedInput& held : judged.released) countStale(held);  // before this one's
  switch (judged.verdict) {
    case OrderVerdict::Use:
      return true;
    case OrderVerdict::Stale:
      countStale(received);
      return false;
    case OrderVerdict::HeldAhead:
      // One forward glitch: taken, it would make the on-time inputs after it a jump back.
      ++counters_.held_ahead;
      sink_.note({EngineNote::HeldAhead, source, stamp});
      return false;
    case OrderVerdict::HeldInRun:
      return false;  // counted when the run is a jump or breaks
    case OrderVerdict::JumpedBack:
      confirming = std::move(judged.confirming);
      restartTimeline(source, stamp);
      order_rule_.observeLag(sourceIndex(source), clock_, stamp);  // after a restart forgot it
      return true;
  }
  return false;
}

void AttitudeEngine::countStale(const ReceivedInput& dropped) {
  ++counters_.dropped_stale;
  sink_.note({EngineNote::Stale, dropped.input.source, dropped.input.stamp});
}

void AttitudeEngine::restartTimeline(Source source, Stamp stamp) {
  ++counters_.jumps_back;
  sink_.note({EngineNote::StampsJumpedBack, source, stamp});
  const Propagator::InputOrderRestart restart = propagator_->restartInputOrder(source);
  counters_.dropped_stale += restart.dropped;  // its queued inputs from the old timeline
  if (restart.time_restarts) {
    // The model's time is the inputs' (kinematic): it starts again with them, from the initial
    // state, and the outputs' stamps start again too.
    ++counters_.resets;
    resetState(true);
    order_rule_.startAgainAt(sourceIndex(source), stamp, timePolicyOf(config_));
  }
}

std::optional<double> AttitudeEngine::inputLag(Source source) const {
  return order_rule_.lag(sourceIndex(source));
}

bool AttitudeEngine::submitBias(Stamp stamp, const Eigen::Vector3d& gyro_bias_B) {
  if (!gyro_bias_B.allFinite() || !(gyro_bias_B.norm() <= kMaxBodyRate) || tooFarAhead(stamp)) {
    ++counters_.rejected_bias;  // like an input: more than max_future ahead is refused
    return false;
  }
  const auto pushed = pending_gyro_bias_.push(stamp, gyro_bias_B);
  if (!pushed.kept || pushed.dropped) ++counters_.bias_queue_full;
  return pushed.kept;
}

const Eigen::Vector3d& AttitudeEngine::biasAt(Stamp stamp) {
  while (pending_gyro_bias_.due(stamp)) {
    gyro_bias_B_ = pending_gyro_bias_.pop();
    ++counters_.bias_applied;
  }
  return gyro_bias_B_;
}

void AttitudeEngine::countOutcome(StampOutcome outcome, std::optional<Source> source, Stamp stamp) {
  const StampOutcomeRow& row = stampOutcomeRow(outcome);
  const bool input = source.has_value() && row.input != nullptr;
  if (input) ++(counters_.*row.input);
  if (row.event) ++(counters_.*row.event);
  if (row.note && (input || row.event)) sink_.note({*row.note, source, stamp});
  if (outcome == StampOutcome::HeldGap) rebaseIfFar(stamp);  // the state held there
}

// ---------------------------------------------------------------------------------------------
// State
// ---------------------------------------------------------------------------------------------

EngineState AttitudeEngine::state() const {
  EngineState s = propagator_->state();
  s.P_B = error_.P_B;
  if (config_.aiding.use_accel && tilt_known_) {
    // What the filter cannot tell from its own tilt error: the lasting disagreement with the
    // gravity direction, in the tilt plane (the heading's variance is not the direction's).
    const Eigen::Vector3d u = bodyUp(s.q_WB);
    const Eigen::Matrix3d plane = Eigen::Matrix3d::Identity() - u * u.transpose();
    const double own = 0.5 * (plane * s.P_B * plane).trace();
    const double beyond = std::max(0.0, tilt_disagreement_.variance() - own);
    s.P_B = clampOrientationCovariance(s.P_B + beyond * plane);
  }
  if (config_.fixes.estimate_gyro_bias) {
    s.gyro_bias_estimate_B = error_.bias_B;
    s.gyro_bias_stddev_B = gyroBiasStddev();
  }
  return s;
}

EngineState AttitudeEngine::stateAt(Stamp stamp) const {
  EngineState s = state();
  s.stamp = stamp;
  return s;
}

void AttitudeEngine::emitState(Stamp stamp) {
  if (!publishable(stamp, last_published_)) return;
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

void AttitudeEngine::handOn(const Input& input, Stamp stamp,
                            const std::optional<DynamicState>& at) {
  EngineState s = stateAt(stamp);
  if (at) {  // the state at its own stamp, behind the model's
    s.q_WB = at->q_WB;
    s.w_B = at->w_B;
  }
  sink_.inputApplied(input, s);
}

void AttitudeEngine::followCovariance(const ModelResult& result) {
  switch (result.covariance) {
    case ModelResult::Covariance::Unchanged:
      return;
    case ModelResult::Covariance::Anchor:
      anchorCovariance();
      return;
    case ModelResult::Covariance::Step:
      propagateCovariance(result.h, result.w_step, result.input->rate_covariance_B);
      return;
  }
}

void AttitudeEngine::propagateCovariance(double h, const Eigen::Vector3d& w_step,
                                         const Eigen::Matrix3d& rate_covariance_B) {
  const Eigen::Matrix3d& R_B = rate_covariance_B.isZero(0.0) ? default_R_B_ : rate_covariance_B;
  propagateErrorState(error_, h, w_step, R_B, config_.fixes.estimate_gyro_bias,
                      config_.fixes.gyro_bias_random_walk);
}

void AttitudeEngine::resetState(bool forget_time) {
  counters_.dropped_on_reset += propagator_->reset();  // queued inputs dropped, counted
  error_.P_B = initialCovariance();
  error_.P_Bb.setZero();  // the bias estimate stays: it belongs to the gyro, not to the timeline
  replay_.clear();
  // Waiting fixes are stamped before the new anchor now: too old (docs/design.md §6.9), not
  // inputs dropped at the reset.
  counters_.fixes_too_old += pending_fixes_.size();
  pending_fixes_.clear();
  while (!pending_measurements_.empty())
    ++aidingCounters(pending_measurements_.pop().measurement->kind()).too_old;
  tilt_known_ = !config_.aiding.align;  // the initial state again
  last_imu_stamp_.reset();
  linear_acceleration_.reset();
  tilt_disagreement_.reset();
  linear_variance_ = {};
  accel_run_.clear();
  mag_run_.clear();
  if (forget_time) {
    time_.forget();
    last_published_.reset();
    // Runs from an earlier time of the timelines forgotten: never a jump now.
    for (const ReceivedInput& held : order_rule_.forget()) countStale(held);
  }
}

std::string AttitudeEngine::reconfigure(const EngineConfig& next) {
  if (next.model != config_.model) return "model: cannot change while running";
  try {
    checkEngineSettings(next);
    propagator_->reconfigure(next);
  } catch (const std::exception& e) {
    return e.what();
  }
  const Eigen::Vector3d bias_B = config_.gyro_bias_B;  // the topic's bias stays in force
  const bool estimate_changed = next.fixes.estimate_gyro_bias != config_.fixes.estimate_gyro_bias;
  config_ = next;
  // The saved states belong to the old propagator (its integrator, its policy): not replayed.
  replay_.clear();
  if (estimate_changed) resetBiasState();
  config_.gyro_bias_B = bias_B;
  rate_delay_ns_ = rateDelayNs(config_);
  default_R_B_ = defaultRateCovariance(config_);
  keep_history_ = keep_history_ || config_.aiding.use_mag;
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
    time_.pin(stamp);  // a state pinned before any other: time starts here
    propagator_->setState(coreTime(stamp), q_WB, w_B);
  } catch (const std::exception& e) {
    return e.what();
  }
  error_.P_B.setZero();  // pinned: the state is what the caller says it is
  error_.P_Bb.setZero();
  tilt_known_ = true;
  replay_.clear();  // a fix stamped before the pin is too old
  if (keep_history_) replay_.record(ModelStep{}, true);
  emitState(stamp);
  return {};
}

// ---------------------------------------------------------------------------------------------
// Late absolute fixes (docs/design.md §6.9, docs/numerics.md §7.1)
// ---------------------------------------------------------------------------------------------

void AttitudeEngine::countFix(FixOutcome outcome) {
  // Waiting counts nothing: the fix is counted when the rates reach it.
  for (auto counter : fixOutcomeRow(outcome).counters) ++(counters_.*counter);
}

FixOutcome AttitudeEngine::submitFix(Stamp stamp, const Eigen::Quaterniond& q_WB,
                                     const Eigen::Matrix3d& covariance_B) {
  FixOutcome outcome = FixOutcome::Waiting;
  if (!q_WB.coeffs().allFinite() || !(std::abs(q_WB.norm() - 1.0) <= kFixUnitTolerance)) {
    outcome = FixOutcome::BadQuaternion;
  } else if (!validFixCovariance(covariance_B)) {
    outcome = FixOutcome::BadCovariance;
  } else if (tooFarAhead(stamp)) {
    outcome = FixOutcome::Future;  // it would wait for rates that may never come
  }
  if (outcome != FixOutcome::Waiting) {
    countFix(outcome);
    return outcome;
  }
  const double s = config_.fixes.stddev;
  LateFix fix{stamp, q_WB.normalized(),
              covariance_B.isZero(0.0)
                  ? Eigen::Matrix3d(s * s * Eigen::Matrix3d::Identity())
                  : Eigen::Matrix3d(0.5 * (covariance_B + covariance_B.transpose()))};
  keepHistory();
  if (replay_.reaches(stamp)) {
    outcome = replay_.applyInStampOrder(fix);
    countFix(outcome);
    return outcome;
  }
  // Ahead of the newest rate (or before the first): it waits for the rates to reach it.
  const auto pushed = pending_fixes_.push(stamp, fix);
  if (!pushed.kept || pushed.dropped) countFix(FixOutcome::QueueFull);
  return pushed.kept ? FixOutcome::Waiting : FixOutcome::QueueFull;
}

void AttitudeEngine::keepHistory() {
  if (keep_history_) return;
  // Nothing is kept until a fix or a late sample needs it: the history starts at the newest
  // state.
  keep_history_ = true;
  replay_.record(ModelStep{}, true);
}

void AttitudeEngine::applyDueFixes() {
  while (!pending_fixes_.empty() && replay_.reaches(pending_fixes_.frontStamp())) {
    countFix(replay_.applyInStampOrder(pending_fixes_.pop()));
  }
  applyDueMeasurements();
}

}  // namespace attitude_propagator
