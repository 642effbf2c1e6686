#include "attitude_propagator/models/dynamic_scheduler.h"

#include <algorithm>
#include <exception>
#include <iterator>
#include <stdexcept>
#include <utility>
#include <variant>

#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/time/one_state_per_stamp.h"

namespace attitude_propagator {

namespace {

const DynamicConfig& dynamicConfig(const EngineConfig& config) {
  if (!config.dynamic) throw std::invalid_argument("model: dynamic needs a dynamic config");
  return *config.dynamic;
}

}  // namespace

DynamicScheduler::DynamicScheduler(const EngineConfig& config, const TimeBase& time)
    : time_(time),
      dynamic_(dynamicConfig(config)),
      model_name_(dynamic_.modelName()),
      publish_rate_(config.publish_rate),
      max_pending_(config.max_pending),
      grid_budget_(config.grid_budget),
      work_budget_(config.work_budget) {
  pending_.reserve(max_pending_);
}

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

ModelResult DynamicScheduler::submit(const Input& input, std::optional<Stamp> clock) {
  const double t = time_.coreTime(input.stamp);
  // Not anchored: the input anchors, unless the clock is known and behind its stamp; then the
  // clock's next grid stamp anchors, and the input waits for its stamp like any other (an
  // input stamped in the year 2100 must not carry the propagator away from the clock).
  const bool wait_for_clock = !dynamic_.anchored() && clock && input.stamp > *clock;
  if (!wait_for_clock && (!dynamic_.anchored() || t <= dynamic_.time())) {
    return applyDynamic(input);  // anchors, or late (the core places it), or a jump back
  }
  // Ahead of the propagator: held until the clock reaches its stamp, so the state published
  // at a grid stamp sees exactly the inputs stamped up to it.
  ModelResult r;
  if (pending_.size() >= max_pending_) {
    // Full: the input stamped furthest ahead of the clock goes (applying one early would carry
    // the propagator ahead of the clock, and nothing could be published until it caught up).
    r.pending_overflow = 1;
    r.note = EngineNote{EngineNote::PendingFull, input.source, input.stamp};
    if (input.stamp >= pending_.back().stamp) return r;
    pending_.pop_back();
  }
  const auto at =
      std::upper_bound(pending_.begin(), pending_.end(), input.stamp,
                       [](Stamp stamp, const Input& other) { return stamp < other.stamp; });
  pending_.insert(at, input);
  return r;
}

ModelResult DynamicScheduler::applyDynamic(const Input& input) {
  const double t = time_.coreTime(input.stamp);
  // The core places an input that arrives after the clock passed its stamp (transport
  // latency) at the last grid point, and drops one not newer than the stream's previous one.
  const bool late = dynamic_.anchored() && t < dynamic_.time();
  ModelResult r;
  // Before it acts: the state at its own stamp, where the clock had already passed.
  if (late) r.at = recent_.at(t);
  r.outcome = applyToModel(input);
  r.source = input.source;
  r.stamp = input.stamp;
  r.input = &input;
  r.keep_step = true;
  // The grid publishes; the input is handed on with the state at its stamp.
  r.hand_on = stateHoldsAtStamp(*r.outcome);
  if (late && *r.outcome == StampOutcome::Advanced) r.late = 1;
  return r;
}

StampOutcome DynamicScheduler::applyToModel(const Input& input) {
  const double t = time_.coreTime(input.stamp);
  StampOutcome outcome;
  try {
    outcome = input.source == Source::Torque ? dynamic_.setTorque(t, input.value, input.frame)
                                             : dynamic_.setRate(t, input.value);
  } catch (const std::exception&) {
    // The exact torque-free model refuses a non-zero torque: the configuration excludes it
    // (no torque subscription), so this is a programming error caught rather than propagated.
    outcome = StampOutcome::RejectedNonFinite;
  }
  if (input.source == Source::Torque && stateHoldsAtStamp(outcome)) held_torque_ = input;
  return outcome;
}

void DynamicScheduler::takeDueUpTo(Stamp stamp) {
  std::size_t n = 0;
  while (n < pending_.size() && pending_[n].stamp <= stamp) ++n;
  if (n == 0) return;
  // Moved out first: acting on one may reset the engine, which clears the queue, not these.
  due_.insert(due_.end(), std::make_move_iterator(pending_.begin()),
              std::make_move_iterator(pending_.begin() + n));
  pending_.erase(pending_.begin(), pending_.begin() + n);
}

Propagator::InputOrderRestart DynamicScheduler::restartInputOrder(Source source) {
  // The dynamic model's time is the clock's, which did not go back: the source's inputs go on
  // as late inputs. Its queued inputs from the old timeline would come after them: dropped.
  const auto old = std::remove_if(pending_.begin(), pending_.end(),
                                  [source](const Input& i) { return i.source == source; });
  const auto dropped = static_cast<std::size_t>(pending_.end() - old);
  pending_.erase(old, pending_.end());
  return {false, dropped};
}

// ---------------------------------------------------------------------------------------------
// The publish grid
// ---------------------------------------------------------------------------------------------

std::optional<Stamp> DynamicScheduler::firstStampFromClock(Stamp clock) const {
  return gridStamp(gridIndexAtOrBefore(clock, publish_rate_), publish_rate_);
}

void DynamicScheduler::beginDue(Stamp clock, std::optional<Stamp> last_published,
                                bool skip_intermediate) {
  pass_ = Pass{};
  pass_.k_now = gridIndexAtOrBefore(clock, publish_rate_);
  pass_.k = pass_.k_now;
  if (last_published && !skip_intermediate) {
    pass_.k = std::min(gridIndexAtOrBefore(*last_published, publish_rate_) + 1, pass_.k_now);
  }
  pass_.open = true;
}

std::optional<ModelResult> DynamicScheduler::nextDue(std::optional<Stamp> last_published) {
  while (pass_.open && pass_.k <= pass_.k_now) {
    if (!pass_.at_grid_stamp) {
      if (pass_.handled++ == grid_budget_ || pass_.work >= work_budget_) {
        // Bounded work per pass: the rest is published on the next tick or poll.
        pass_.open = false;
        ModelResult r;
        r.deferred_ticks = 1;
        r.note = EngineNote{EngineNote::Deferred, std::nullopt, gridStamp(pass_.k, publish_rate_)};
        return r;
      }
      pass_.at_grid_stamp = true;
      pass_.stamp = gridStamp(pass_.k, publish_rate_);
      takeDueUpTo(pass_.stamp);
    }
    if (!due_.empty()) {  // the inputs stamped up to the grid stamp first, one a call
      acting_ = std::move(due_.front());
      due_.pop_front();
      return applyDynamic(acting_);
    }
    pass_.at_grid_stamp = false;
    ++pass_.k;
    std::optional<ModelResult> r = publishGridStamp(pass_.stamp, last_published);
    pass_.work += dynamic_.lastCallWork();
    if (r) return r;
  }
  pass_.open = false;
  return std::nullopt;
}

std::optional<ModelResult> DynamicScheduler::publishGridStamp(Stamp stamp,
                                                              std::optional<Stamp> last_published) {
  if (!publishable(stamp, last_published)) return std::nullopt;  // the engine would not
  const double t = time_.coreTime(stamp);
  if (dynamic_.anchored() && t < dynamic_.time()) return std::nullopt;  // set_state pinned later
  ModelResult r;
  r.stamp = stamp;
  if (!dynamic_.anchored() || t > dynamic_.time()) {
    r.outcome = dynamic_.advanceTo(t);
    r.keep_step = true;
    if (!stateHoldsAtStamp(*r.outcome)) return r;
  }
  recent_.push(dynamic_.time(), dynamic_.state());
  r.publish = true;  // also when an input stamped exactly here brought the state to it
  return r;
}

void DynamicScheduler::RecentStates::push(double t, const DynamicState& state) {
  if (size_ > 0 && !(t > entry(size_ - 1).t)) return;  // one per time, increasing
  if (size_ < kKept) {
    ring_[(head_ + size_++) % kKept] = {t, state};
  } else {
    ring_[head_] = {t, state};
    head_ = (head_ + 1) % kKept;
  }
}

std::optional<DynamicState> DynamicScheduler::RecentStates::at(double t) const {
  for (std::size_t i = 1; i < size_; ++i) {
    const Entry& a = entry(i - 1);
    const Entry& b = entry(i);
    if (t < a.t || t > b.t) continue;
    const double s = (t - a.t) / (b.t - a.t);
    DynamicState x;
    x.q_WB = a.state.q_WB.slerp(s, b.state.q_WB);
    x.w_B = (1.0 - s) * a.state.w_B + s * b.state.w_B;
    return x;
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// State
// ---------------------------------------------------------------------------------------------

void DynamicScheduler::setState(double t, const Eigen::Quaterniond& q_WB,
                                const Eigen::Vector3d& w_B) {
  dynamic_.setState(t, DynamicState{q_WB, w_B});
  recent_.clear();
}

std::size_t DynamicScheduler::reset() {
  const std::size_t dropped = pending_.size();  // every input is accounted for
  dynamic_.reset();
  pending_.clear();
  held_torque_.reset();
  recent_.clear();
  return dropped;
}

void DynamicScheduler::reconfigure(const EngineConfig& next) {
  DynamicPropagator d(dynamicConfig(next));
  if (dynamic_.anchored()) {
    const double t = dynamic_.time();
    d.setState(t, dynamic_.state());
    const double timeout = next.dynamic->torque_timeout;
    if (held_torque_ && !(timeout > 0.0 && t - time_.coreTime(held_torque_->stamp) >= timeout)) {
      // At its own stamp, behind the new anchor: placed as a late input, it acts from the
      // anchor. Whether a torque in transit is newer is its source's order, which lives in the
      // engine (SourceTimeline) and outlives this propagator.
      d.setTorque(time_.coreTime(held_torque_->stamp), held_torque_->value, held_torque_->frame);
    }
  }
  dynamic_ = std::move(d);
  recent_.clear();
  model_name_ = dynamic_.modelName();
  publish_rate_ = next.publish_rate;
  max_pending_ = next.max_pending;
  grid_budget_ = next.grid_budget;
  work_budget_ = next.work_budget;
}

// ---------------------------------------------------------------------------------------------
// Late fixes (docs/design.md §6.9): the steps are the inputs applied and the advances to grid
// stamps, so a replay repeats exactly the calls that made the state; the knots depend only on
// them (§4.4), so the state after a replay is the one a fix on time would have given.
// ---------------------------------------------------------------------------------------------

std::optional<double> DynamicScheduler::savedTime() const {
  if (!dynamic_.anchored()) return std::nullopt;
  return dynamic_.time();
}

void DynamicScheduler::save(ModelSnapshot& into) const {
  if (auto* saved = std::get_if<DynamicReplayState>(&into)) {
    saved->dynamic = dynamic_;  // into the slot's own storage
    saved->held_torque = held_torque_;
    return;
  }
  into = DynamicReplayState{dynamic_, held_torque_};
}

void DynamicScheduler::restore(const ModelSnapshot& from) {
  if (const auto* saved = std::get_if<DynamicReplayState>(&from)) {
    dynamic_ = saved->dynamic;
    held_torque_ = saved->held_torque;
    recent_.clear();
  }
}

bool DynamicScheduler::advanceForFix(double t) {
  // From a saved state short of the next step: no input acts in between, so the state at t is
  // the last knot advanced to t, as the live model had it there.
  if (dynamic_.anchored() && t > dynamic_.time()) dynamic_.advanceTo(t);
  return true;
}

ModelResult DynamicScheduler::replay(const ModelStep& step) {
  if (step.advance) {
    dynamic_.advanceTo(time_.coreTime(step.input.stamp));
  } else {
    applyToModel(step.input);
  }
  return ModelResult{};  // nothing the engine keeps: the dynamic model has no covariance
}

EngineState DynamicScheduler::state() const {
  EngineState s;
  s.q_WB = dynamic_.state().q_WB;
  s.w_B = dynamic_.state().w_B;
  s.norm_error = dynamic_.normError();
  s.steps = dynamic_.steps();
  s.M_B = dynamic_.angularMomentum_B();
  s.kinetic_energy = dynamic_.kineticEnergy();
  return s;
}

}  // namespace attitude_propagator
