#include "attitude_propagator/engine.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/quaternion.h"

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

const TimePolicy& policyOf(const EngineConfig& c) {
  return c.dynamic ? c.dynamic->time_policy : c.kinematic.time_policy;
}

/// rate_delay in nanoseconds, or std::invalid_argument: a delay longer than the longest gap
/// integrated across would put every sample behind the one before a gap.
Stamp checkedRateDelay(const EngineConfig& c) {
  const double max_dt = policyOf(c).max_dt;
  if (!(c.rate_delay >= 0.0 && c.rate_delay <= max_dt)) {
    throw std::invalid_argument("rate_delay: accepted: 0 to max_dt = " + std::to_string(max_dt) +
                                " s, got " + std::to_string(c.rate_delay));
  }
  return static_cast<Stamp>(std::llround(c.rate_delay * 1e9));
}

}  // namespace

const char* sourceName(Source source) {
  switch (source) {
    case Source::Imu:
      return "imu/data_raw";
    case Source::Twist:
      return "body_twist";
    case Source::Torque:
      return "torque";
  }
  return "input";
}

AttitudeEngine::AttitudeEngine(const EngineConfig& config, EngineSink& sink)
    : config_(config), sink_(sink) {
  if (config_.model == Model::Dynamic) {
    if (!config_.dynamic) throw std::invalid_argument("model: dynamic needs a dynamic config");
    dynamic_.emplace(*config_.dynamic);
    model_name_ = dynamic_->modelName();
  } else {
    kinematic_.emplace(config_.kinematic);
    model_name_ = "kinematic";
  }
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
  const bool fifo_reads = config_.model == Model::Kinematic &&
                          config_.kinematic.stamp_filter == StampFilter::SensorClock;
  for (Source s : {Source::Imu, Source::Twist}) timeline(s).allowRepeatedStamps(fifo_reads);
  default_R_B_ = config_.rate_stddev * config_.rate_stddev * Eigen::Matrix3d::Identity();
  pending_.reserve(config_.max_pending);
  P_B_ = initialCovariance();
}

Eigen::Matrix3d AttitudeEngine::initialCovariance() const {
  const double s = config_.initial_orientation_stddev;
  return clampOrientationCovariance(s * s * Eigen::Matrix3d::Identity());
}

AttitudeEngine::~AttitudeEngine() = default;

Integrator AttitudeEngine::integrator() const {
  return dynamic_ ? dynamic_->integrator() : kinematic_->integrator();
}

// ---------------------------------------------------------------------------------------------
// Time
// ---------------------------------------------------------------------------------------------

double AttitudeEngine::coreTime(Stamp stamp) {
  // Whole seconds keep the publish grid exact in core time.
  if (!origin_) origin_ = stamp - stamp % kNsPerSecond;
  return static_cast<double>(stamp - *origin_) * 1e-9;
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
    if (kinematic_) {
      kinematic_->setState(t, held.q_WB, held.w_B);
    } else {
      dynamic_->setState(t, DynamicState{held.q_WB, held.w_B});
    }
  } catch (const std::exception&) {
    resetState(true);  // a held state is always valid; should it not be, start afresh
  }
}

Stamp AttitudeEngine::gridStamp(std::int64_t k) const {
  // long double holds nanoseconds since the epoch exactly (64-bit mantissa on x86).
  return static_cast<Stamp>(std::llround(static_cast<long double>(k) * 1e9L /
                                         static_cast<long double>(config_.publish_rate)));
}

std::int64_t AttitudeEngine::gridIndexAtOrBefore(Stamp now) const {
  auto k = static_cast<std::int64_t>(std::floor(
      static_cast<long double>(now) * static_cast<long double>(config_.publish_rate) / 1e9L));
  // The rounding of the grid stamps themselves moves k by one at most.
  if (gridStamp(k) > now) --k;
  if (gridStamp(k + 1) <= now) ++k;
  return k;
}

bool AttitudeEngine::clockWentBack(Stamp now) {
  const double threshold = policyOf(config_).backward_jump;
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
  const double max_dt = policyOf(config_).max_dt;
  const bool jumped = !back && clock_ && static_cast<double>(now - *clock_) * 1e-9 > max_dt;
  advanceClock(now, back);
  if (dynamic_) publishDue(jumped);
}

void AttitudeEngine::poll(Stamp now) {
  if (now <= 0) return;
  advanceClock(now, clockWentBack(now));
  if (dynamic_) publishDue(false);
}

void AttitudeEngine::drain() {
  if (dynamic_) publishDue(false);
}

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
  if (kinematic_) {
    submitKinematic(input);
  } else {
    submitDynamic(input);
  }
}

bool AttitudeEngine::inOrder(Source source, Stamp stamp) {
  SourceTimeline& line = timeline(source);
  switch (line.judge(stamp, policyOf(config_))) {
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
  if (kinematic_) {
    // The rates stamp the kinematic model's states: its time starts again with them (a looped
    // bag), from the initial state, and the outputs' stamps start again too.
    ++counters_.resets;
    resetState(true);
    timeline(source).judge(stamp, policyOf(config_));  // forgotten with the rest: the first
    return;
  }
  // The dynamic model's time is the clock's, which did not go back: the source's inputs go on
  // as late inputs. Its queued inputs from the old timeline would come after them: dropped.
  const auto old = std::remove_if(pending_.begin(), pending_.end(),
                                  [source](const Input& i) { return i.source == source; });
  counters_.dropped_stale += static_cast<std::uint64_t>(pending_.end() - old);
  pending_.erase(old, pending_.end());
  dynamic_->restartInputOrder();
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

void AttitudeEngine::submitKinematic(const Input& input) {
  const double t = coreTime(input.stamp);
  // time() is only defined once anchored (the window is empty before).
  const double t_before = kinematic_->anchored() ? kinematic_->time() : 0.0;
  const Eigen::Quaterniond q_before = kinematic_->orientation();
  const StampOutcome outcome = kinematic_->addSample(t, input.value);
  if (!handleOutcome(outcome, input.source, input.stamp)) return;
  if (outcome == StampOutcome::Advanced) {
    // The step's own rotation drives the covariance, whatever the integrator did inside it.
    const double h = t - t_before;
    const Eigen::Vector3d w_step = logMap(q_before.conjugate() * kinematic_->orientation()) / h;
    const Eigen::Matrix3d& R_B =
        input.rate_covariance_B.isZero(0.0) ? default_R_B_ : input.rate_covariance_B;
    P_B_ = propagateOrientationCovariance(P_B_, h, w_step, R_B);
  } else if (outcome == StampOutcome::Anchored) {
    P_B_ = initialCovariance();  // the initial state again, as uncertain as configured
  }
  // With the stamp filter on, or averages stamped at their start or midpoint, the state holds
  // where the propagator put it, not at the input's stamp.
  const Stamp stamp = kinematic_->movesStamps() && origin_
                          ? *origin_ + static_cast<Stamp>(std::llround(kinematic_->time() * 1e9))
                          : input.stamp;
  emitState(stamp);
  sink_.inputApplied(input, stateAt(stamp));
}

void AttitudeEngine::submitDynamic(const Input& input) {
  const double t = coreTime(input.stamp);
  // Not anchored: the input anchors, unless the clock is known and behind its stamp; then the
  // clock's next grid stamp anchors, and the input waits for its stamp like any other (an
  // input stamped in the year 2100 must not carry the propagator away from the clock).
  const bool wait_for_clock = !dynamic_->anchored() && clock_ && input.stamp > *clock_;
  if (!wait_for_clock && (!dynamic_->anchored() || t <= dynamic_->time())) {
    applyDynamic(input);  // anchors, or late (the core places it), or a jump back
    return;
  }
  // Ahead of the propagator: held until the clock reaches its stamp, so the state published
  // at a grid stamp sees exactly the inputs stamped up to it.
  if (pending_.size() >= config_.max_pending) {
    // Full: the input stamped furthest ahead of the clock goes (applying one early would carry
    // the propagator ahead of the clock, and nothing could be published until it caught up).
    ++counters_.pending_overflow;
    sink_.note({EngineNote::PendingFull, input.source, input.stamp});
    if (input.stamp >= pending_.back().stamp) return;
    pending_.pop_back();
  }
  const auto at =
      std::upper_bound(pending_.begin(), pending_.end(), input.stamp,
                       [](Stamp stamp, const Input& other) { return stamp < other.stamp; });
  pending_.insert(at, input);
}

void AttitudeEngine::applyDynamic(const Input& input) {
  const double t = coreTime(input.stamp);
  // The core places an input that arrives after the clock passed its stamp (transport
  // latency) at the last grid point, and drops one not newer than the stream's previous one.
  const bool late = dynamic_->anchored() && t < dynamic_->time();
  StampOutcome outcome;
  try {
    outcome = input.source == Source::Torque ? dynamic_->setTorque(t, input.value, input.frame)
                                             : dynamic_->setRate(t, input.value);
  } catch (const std::exception&) {
    // The exact torque-free model refuses a non-zero torque: the configuration excludes it
    // (no torque subscription), so this is a programming error caught rather than propagated.
    outcome = StampOutcome::RejectedNonFinite;
  }
  if (late && outcome == StampOutcome::Advanced) ++counters_.late;
  if (input.source == Source::Torque && stateHoldsAtStamp(outcome)) held_torque_ = input;
  if (handleOutcome(outcome, input.source, input.stamp)) {
    sink_.inputApplied(input, stateAt(input.stamp));
  }
}

void AttitudeEngine::applyPendingUpTo(Stamp stamp) {
  std::size_t n = 0;
  while (n < pending_.size() && pending_[n].stamp <= stamp) ++n;
  if (n == 0) return;
  // Moved out first: applying may reset the engine, which clears the queue.
  std::vector<Input> due(std::make_move_iterator(pending_.begin()),
                         std::make_move_iterator(pending_.begin() + n));
  pending_.erase(pending_.begin(), pending_.begin() + n);
  for (const Input& input : due) applyDynamic(input);
}

// ---------------------------------------------------------------------------------------------
// The dynamic model's publish grid
// ---------------------------------------------------------------------------------------------

void AttitudeEngine::publishDue(bool skip_intermediate) {
  if (!clock_) return;
  const std::int64_t k_now = gridIndexAtOrBefore(*clock_);
  std::int64_t k = k_now;
  if (last_published_ && !skip_intermediate) {
    k = std::min(gridIndexAtOrBefore(*last_published_) + 1, k_now);
  }
  std::size_t handled = 0;
  std::uint64_t work = 0;
  for (; k <= k_now; ++k) {
    if (handled++ == config_.grid_budget || work >= config_.work_budget) {
      // Bounded work per call: the rest is published on the next tick or poll.
      ++counters_.deferred_ticks;
      sink_.note({EngineNote::Deferred, std::nullopt, gridStamp(k)});
      return;
    }
    publishGridStamp(gridStamp(k));
    work += dynamic_->lastCallWork();
  }
}

void AttitudeEngine::publishGridStamp(Stamp stamp) {
  applyPendingUpTo(stamp);
  if (last_published_ && stamp <= *last_published_) return;
  const double t = coreTime(stamp);
  if (dynamic_->anchored() && t < dynamic_->time()) return;  // set_state pinned a later time
  if (!dynamic_->anchored() || t > dynamic_->time()) {
    const StampOutcome outcome = dynamic_->advanceTo(t);
    if (!handleOutcome(outcome, std::nullopt, stamp)) return;
  }
  emitState(stamp);  // also when an input stamped exactly here brought the state to it
}

// ---------------------------------------------------------------------------------------------
// State
// ---------------------------------------------------------------------------------------------

EngineState AttitudeEngine::state() const {
  EngineState s;
  if (kinematic_) {
    s.q_WB = kinematic_->orientation();
    s.w_B = kinematic_->rate();
    s.norm_error = kinematic_->normError();
    s.steps = kinematic_->steps();
  } else {
    s.q_WB = dynamic_->state().q_WB;
    s.w_B = dynamic_->state().w_B;
    s.norm_error = dynamic_->normError();
    s.steps = dynamic_->steps();
    s.M_B = dynamic_->angularMomentum_B();
    s.kinetic_energy = dynamic_->kineticEnergy();
  }
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

double AttitudeEngine::energyDrift() const { return dynamic_ ? dynamic_->energyDrift() : 0.0; }

double AttitudeEngine::momentumDrift() const { return dynamic_ ? dynamic_->momentumDrift() : 0.0; }

void AttitudeEngine::resetState(bool forget_time) {
  counters_.dropped_on_reset += pending_.size();  // every input is accounted for
  if (kinematic_) kinematic_->reset();
  if (dynamic_) dynamic_->reset();
  pending_.clear();
  held_torque_.reset();
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
    if (kinematic_) {
      KinematicPropagator k(next.kinematic);
      if (kinematic_->anchored()) {
        k.setState(kinematic_->time(), kinematic_->orientation(), kinematic_->rate());
      }
      kinematic_.emplace(k);
    } else {
      DynamicPropagator d(*next.dynamic);
      if (dynamic_->anchored()) {
        const double t = dynamic_->time();
        d.setState(t, dynamic_->state());
        const double timeout = next.dynamic->torque_timeout;
        if (held_torque_ && !(timeout > 0.0 && t - coreTime(held_torque_->stamp) >= timeout)) {
          // At its own stamp, behind the new anchor: it acts from the anchor, and a torque in
          // transit stamped after it is still newer, not stale.
          d.setTorque(coreTime(held_torque_->stamp), held_torque_->value, held_torque_->frame);
        }
      }
      dynamic_ = std::move(d);
      model_name_ = dynamic_->modelName();
    }
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
    const double t = coreTime(stamp);
    if (kinematic_) {
      kinematic_->setState(t, q_WB, w_B);
    } else {
      dynamic_->setState(t, DynamicState{q_WB, w_B});
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  P_B_.setZero();  // pinned: the state is what the caller says it is
  emitState(stamp);
  return {};
}

}  // namespace attitude_propagator
