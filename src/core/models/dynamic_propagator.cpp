#include "attitude_propagator/models/dynamic_propagator.h"

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_propagator/models/sample_door.h"
#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/numerics/torque_free_motion.h"

namespace attitude_propagator {

namespace {

/// The names of the dynamic methods that take a torque (all, when `torque` is false).
std::string dynamicNames(bool torque) {
  std::vector<std::string> names{"auto"};
  for (Integrator m : integratorsFor(Model::Dynamic)) {
    if (!torque || integratorInfo(m).takes_torque) names.push_back(integratorName(m));
  }
  return joinNames(names);
}

Integrator resolveIntegrator(const DynamicConfig& config) {
  // "No more than the scene needs": the table's choice for auto is the exact
  // torque-free motion when no torque can arrive, otherwise rk4.
  if (config.integrator == Integrator::Auto) {
    return autoIntegrator(Model::Dynamic, config.torque_input);
  }
  const IntegratorInfo& method = integratorInfo(config.integrator);
  if (method.dynamic_step == nullptr) {
    throw std::invalid_argument(
        "integrator: '" + integratorName(config.integrator) +
        "' is not a dynamic integrator; accepted for the dynamic model: " + dynamicNames(false));
  }
  if (config.torque_input && !method.takes_torque) {
    throw std::invalid_argument("integrator: '" + integratorName(config.integrator) +
                                "' takes no torque and cannot run with torque_input; accepted "
                                "with torque: " +
                                dynamicNames(true));
  }
  return config.integrator;
}

void requirePositiveFinite(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(name) + ": must be positive and finite, got " +
                                std::to_string(value));
  }
}

/// x with its quaternion normalised, or std::invalid_argument naming what is wrong.
DynamicState checkedState(const DynamicState& x, const std::string& what) {
  if (!x.w_B.allFinite()) throw std::invalid_argument(what + ": non-finite angular velocity");
  const std::optional<Eigen::Quaterniond> q = safeNormalized(x.q_WB);
  if (!q) {
    throw std::invalid_argument(what + ": the orientation must be a finite, non-zero quaternion");
  }
  if (!(x.w_B.norm() <= kMaxBodyRate)) {
    throw std::invalid_argument(what + ": angular velocity above kMaxBodyRate = 1e5 rad/s");
  }
  return DynamicState{*q, x.w_B};
}

}  // namespace

// The state is kept at "knots": committed states at times that depend only on the inputs,
// namely the anchor, the grid points anchor + n max_step, the stamps of torque and rate
// samples, and the instants a torque times out. The state at any stamp t is the last knot
// before t advanced by one partial step to t, never committed, so it does not depend on which
// stamps the caller visited on its way to t. A method exact at any step length
// (`exact`) has no grid points: its step from the knot evaluates the stepper's cached closed
// form through the knot.
//
// Torque over a step: a torque sample at stamp s is in force on [s, s + torque_timeout) (or
// from s on with no timeout). The sample's stamp and its expiry are knots, so every step
// (whole or partial) lies inside one interval of constant torque and uses the torque in force
// at its start. A torque sample thus acts from its own stamp, not from the next grid point,
// and the grid after it is unchanged.
struct DynamicPropagator::Impl {
  DynamicConfig config;
  Integrator integrator;
  DynamicStepper stepper;
  DynamicState initial;

  bool anchored = false;
  double grid_origin = 0.0;
  std::int64_t grid_index = 0;  // the last grid point at or before knot_time
  double knot_time = 0.0;
  PrincipalState knot;
  double knot_hint = 0.0;  // dopri5's step-size suggestion after the steps up to the knot
  double time = 0.0;
  PrincipalState current;
  DynamicState current_B;

  bool torque_set = false;
  // Where the torque took effect, max(stamp, knot): the timeout runs from there.
  double torque_stamp = -std::numeric_limits<double>::infinity();
  PrincipalTorque torque;
  // The stamps of the last accepted samples, for the out-of-order check: a late sample that
  // took effect at a later knot must not make a newer late sample look stale.

  std::uint64_t steps = 0;
  std::uint64_t failed_steps = 0;
  // After a failed interval, the same state under the same inputs fails again: until an input
  // or a new anchor changes something, an interval at least half as long fails at once, with
  // no work (a body spun past what the integrator can follow must not cost a budget per tick).
  bool stuck = false;
  double stuck_interval = 0.0;
  StepStatus last_failure = StepStatus::Ok;
  StepStatus failure = StepStatus::Ok;  // why the current call's integration failed
  std::uint64_t work = 0;               // work units spent by the current call
  double norm_error = 0.0;
  double energy0 = 0.0;
  double momentum0 = 0.0;

  explicit Impl(const DynamicConfig& c)
      : config(c),
        integrator(resolveIntegrator(c)),
        stepper(integrator, c.body, c.tolerance),
        initial(checkedState(c.initial, "initial state")) {
    requirePositiveFinite(c.max_step, "max_step");
    requirePositiveFinite(c.tolerance, "tolerance");
    if (c.tolerance < kMinTolerance || c.tolerance > kMaxTolerance) {
      // Below round-off dopri5's control cannot converge; above it, it is no control at all.
      throw std::invalid_argument("tolerance: must be in [" + std::to_string(kMinTolerance) + ", " +
                                  std::to_string(kMaxTolerance) + "], got " +
                                  std::to_string(c.tolerance));
    }
    requirePositiveFinite(c.time_policy.max_dt, "max_dt");
    requirePositiveFinite(c.time_policy.backward_jump, "backward_jump");
    if (!(c.torque_timeout >= 0.0) || !std::isfinite(c.torque_timeout)) {
      throw std::invalid_argument("torque_timeout: must be zero (hold forever) or positive, got " +
                                  std::to_string(c.torque_timeout));
    }
    const double needed = c.time_policy.max_dt / c.max_step + kBudgetHeadroomSteps;
    if (!(static_cast<double>(c.step_budget) >= needed)) {
      throw std::invalid_argument(
          "step_budget: " + std::to_string(c.step_budget) + " cannot cover max_dt / max_step + " +
          std::to_string(static_cast<int>(kBudgetHeadroomSteps)) + " = " + std::to_string(needed) +
          " steps; raise max_step or step_budget, or lower max_dt");
    }
    if (!startsFrom(initial)) {
      throw std::invalid_argument("initial state: integrator '" + integratorName(integrator) +
                                  "' cannot start from it (its closed form cannot be evaluated)");
    }
    pin(0.0, initial);
    anchored = false;
  }

  /// A method exact at any step length (the table's kExactFlow) needs no grid: its state at t
  /// is one step from the knot.
  bool gridded() const { return !(integratorInfo(integrator).keeps & keeps::kExactFlow); }

  /// Whether the method can step from x: a zero-length step succeeds (the closed form, for
  /// one, cannot be set up from every state whose constants leave the doubles).
  bool startsFrom(const DynamicState& x) const {
    PrincipalState y = stepper.toPrincipal(x);
    return stepper.tryStepPrincipal(y, PrincipalTorque{}, 0.0, 1) == StepStatus::Ok;
  }

  double gridTime(std::int64_t n) const {
    return grid_origin + static_cast<double>(n) * config.max_step;
  }

  /// Torque in force at time s (the held sample, or zero once it has timed out).
  PrincipalTorque torqueAt(double s) const {
    if (!torque_set || (config.torque_timeout > 0.0 && s >= torqueExpiry())) {
      return PrincipalTorque{};
    }
    return torque;
  }
  double torqueExpiry() const { return torque_stamp + config.torque_timeout; }

  /// Makes x at time t the anchor: the grid restarts at t.
  void pin(double t, const DynamicState x) {  // by value: x may be current_B
    stuck = false;
    anchored = true;
    grid_origin = t;
    grid_index = 0;
    knot_hint = 0.0;
    setKnot(t, stepper.toPrincipal(x));
    current_B = x;  // exactly the state given, not its round trip through P
    energy0 = config.body.kineticEnergy(x.w_B);
    momentum0 = config.body.angularMomentum_B(x.w_B).norm();
  }

  /// Commits x as the knot at t (and the current state).
  void setKnot(double t, const PrincipalState& x) {
    knot_time = t;
    knot = x;
    setCurrent(t, x);
  }

  void setCurrent(double t, const PrincipalState& x) {
    time = t;
    current = x;
    current_B = stepper.fromPrincipal(x);
  }

  /// Starts the work count of a public call.
  void beginCall() {
    work = 0;
    failure = StepStatus::Ok;
  }

  /// One step from x over h with the torque in force at `from`, within the call's budget.
  /// False (x unchanged, `failure` set) if the integrator could not complete it.
  bool step(PrincipalState& x, double from, double h) {
    if (work >= config.step_budget) {
      failure = StepStatus::OverBudget;
      return false;
    }
    StepInfo info;
    stepper.setStepSizeHint(knot_hint);
    const StepStatus status =
        stepper.tryStepPrincipal(x, torqueAt(from), h, config.step_budget - work, &info);
    work += info.attempts;
    ++steps;
    if (status != StepStatus::Ok) {
      failure = status;
      return false;
    }
    norm_error = info.norm_error;
    return true;
  }

  /// Commits the knots up to t (t >= knot_time) and sets the current state at t. False if a
  /// step failed: knots up to the failure may be committed, the current state is unchanged.
  bool advanceState(double t) {
    for (;;) {
      bool on_grid = gridded();
      double next = on_grid ? gridTime(grid_index + 1) : std::numeric_limits<double>::infinity();
      if (torque_set && config.torque_timeout > 0.0) {
        const double expiry = torqueExpiry();
        if (expiry > knot_time && expiry < next) {
          next = expiry;
          on_grid = false;
        }
      }
      if (next > t) break;
      if (!step(knot, knot_time, next - knot_time)) return false;
      knot_hint = stepper.stepSizeHint();
      knot_time = next;
      if (on_grid) ++grid_index;
    }
    PrincipalState x = knot;
    if (t > knot_time && !step(x, knot_time, t - knot_time)) return false;
    setCurrent(t, x);
    return true;
  }

  /// Commits the state at t (knot_time <= t <= time) as a knot. False if the step failed.
  bool commitAt(double t) {
    if (t == knot_time) return true;
    PrincipalState x = knot;
    if (!step(x, knot_time, t - knot_time)) return false;
    knot = x;
    knot_hint = stepper.stepSizeHint();
    knot_time = t;
    return true;
  }

  /// The integration up to t failed: like a gap, the state held at time() holds at t and
  /// anchors there.
  StampOutcome failAndHold(double t, const DynamicState& held) {
    ++failed_steps;
    last_failure = failure;
    const double interval = t - time;
    pin(t, held);
    stuck = true;
    stuck_interval = interval;
    return StampOutcome::FailedStep;
  }

  StampOutcome advanceTo(double t) {
    if (!std::isfinite(t)) return StampOutcome::RejectedNonFinite;
    if (!anchored) {
      pin(t, initial);
      return StampOutcome::Anchored;
    }
    switch (classifyStamp(time, t, config.time_policy)) {
      case StampClass::Stale:
        return StampOutcome::DroppedStale;
      case StampClass::Gap:
        // Not integrated across: the state at the last stamp holds at t, a new anchor.
        pin(t, current_B);
        return StampOutcome::HeldGap;
      case StampClass::Forward: {
        const DynamicState held = current_B;
        if (stuck && t - time >= 0.5 * stuck_interval) {
          failure = last_failure;  // the same reason as the interval that failed
          return failAndHold(t, held);
        }
        return advanceState(t) ? StampOutcome::Advanced : failAndHold(t, held);
      }
    }
    return StampOutcome::DroppedStale;
  }

  /// Where an input stamped t takes effect: advances to t when t is ahead, and for a stamp
  /// behind time() by any amount (an input that arrived after the clock passed its stamp: a
  /// transport delay, a starved process, a sensor clock behind the node's) inserts a knot at t,
  /// or at the last knot if t is older, and recomputes the current state. Whether the input is
  /// newer than the previous one of its source is the engine's rule (SourceTimeline), not this.
  StampOutcome placeInput(double t) {
    if (!anchored || t > time) return advanceTo(t);
    return StampOutcome::Advanced;
  }

  /// Applies an input at max(t, knot_time) when t <= time(); see placeInput. If the steps to
  /// the input's knot or on from it fail, the state held at time() anchors there and the
  /// input applies from that anchor; returns false then.
  template <typename Apply>
  bool insertKnot(double t, Apply apply) {
    const double now = time;
    const DynamicState held = current_B;
    if (commitAt(std::max(t, knot_time))) {
      apply();
      stuck = false;  // an input changed what the integrator faces
      if (now <= knot_time) {
        setCurrent(knot_time, knot);
        return true;
      }
      if (advanceState(now)) return true;
    }
    failAndHold(now, held);
    apply();  // at the new anchor: knot_time == now
    stuck = false;
    setCurrent(knot_time, knot);
    return false;
  }

  void clearInputs() {
    torque_set = false;
    torque = PrincipalTorque{};
    torque_stamp = -std::numeric_limits<double>::infinity();
  }
};

DynamicPropagator::DynamicPropagator(const DynamicConfig& config)
    : impl_(std::make_unique<Impl>(config)) {}

DynamicPropagator::~DynamicPropagator() = default;
DynamicPropagator::DynamicPropagator(DynamicPropagator&&) noexcept = default;
DynamicPropagator& DynamicPropagator::operator=(DynamicPropagator&&) noexcept = default;

DynamicPropagator::DynamicPropagator(const DynamicPropagator& other)
    : impl_(std::make_unique<Impl>(*other.impl_)) {}

DynamicPropagator& DynamicPropagator::operator=(const DynamicPropagator& other) {
  if (this == &other) return *this;
  if (impl_ && other.impl_) {
    *impl_ = *other.impl_;  // into the existing Impl: no allocation per history entry
  } else {
    impl_ = other.impl_ ? std::make_unique<Impl>(*other.impl_) : nullptr;
  }
  return *this;
}

Integrator DynamicPropagator::integrator() const { return impl_->integrator; }

std::string DynamicPropagator::modelName() const {
  if (impl_->gridded()) {
    return "numerical_" + integratorName(impl_->integrator);
  }
  const RigidBody& body = impl_->config.body;
  if (body.isSphere(TorqueFreeMotion::kRelativeSymmetry)) return "exact_sphere";
  if (body.isSymmetric(TorqueFreeMotion::kRelativeSymmetry)) return "exact_symmetric_top";
  return "exact_triaxial";
}

StampOutcome DynamicPropagator::advanceTo(double t) {
  impl_->beginCall();
  return impl_->advanceTo(t);
}

StampOutcome DynamicPropagator::setTorque(double t, const Eigen::Vector3d& tau, TorqueFrame frame) {
  Impl& d = *impl_;
  d.beginCall();
  if (const auto refused = refusedSample(t, tau, doorBound(true))) return *refused;
  if (!integratorInfo(d.integrator).takes_torque && !tau.isZero(0.0)) {
    throw std::logic_error("DynamicPropagator::setTorque: integrator '" +
                           integratorName(d.integrator) + "' cannot take a torque");
  }
  const StampOutcome outcome = d.placeInput(t);
  if (!stateHoldsAtStamp(outcome)) return outcome;
  TorqueInput input;
  input.tau = tau;
  input.frame = frame;
  const bool ok = d.insertKnot(t, [&d, &input, t]() {
    d.torque = d.stepper.toPrincipal(input);
    d.torque_set = true;
    d.torque_stamp = std::max(t, d.knot_time);
  });
  return ok ? outcome : StampOutcome::FailedStep;
}

StampOutcome DynamicPropagator::setRate(double t, const Eigen::Vector3d& w_B) {
  Impl& d = *impl_;
  d.beginCall();
  if (const auto refused = refusedSample(t, w_B, doorBound(false))) return *refused;
  const StampOutcome outcome = d.placeInput(t);
  if (!stateHoldsAtStamp(outcome)) return outcome;
  const bool ok = d.insertKnot(t, [&d, &w_B, t]() {
    d.knot.w_P = d.config.body.q_BP().conjugate() * w_B;
    const DynamicState x = d.stepper.fromPrincipal(d.knot);
    d.energy0 = d.config.body.kineticEnergy(x.w_B);
    d.momentum0 = d.config.body.angularMomentum_B(x.w_B).norm();
  });
  return ok ? outcome : StampOutcome::FailedStep;
}

void DynamicPropagator::setState(double t, const DynamicState& state) {
  if (!std::isfinite(t)) throw std::invalid_argument("set_state: non-finite stamp");
  const DynamicState x = checkedState(state, "set_state");
  if (!impl_->startsFrom(x)) {
    throw std::invalid_argument("set_state: integrator '" + integratorName(impl_->integrator) +
                                "' cannot start from this state");
  }
  impl_->pin(t, x);
}

void DynamicPropagator::reset() {
  impl_->clearInputs();
  impl_->pin(0.0, impl_->initial);
  impl_->anchored = false;
}

void DynamicPropagator::correctOrientation(const Eigen::Quaterniond& q_WB) {
  Impl& d = *impl_;
  const std::optional<Eigen::Quaterniond> unit = safeNormalized(q_WB);
  if (!d.anchored || !unit) return;
  d.beginCall();
  // The current state becomes a knot (the same step from the last knot that computed it), so
  // the correction acts at time() and the grid after it is unchanged.
  if (!d.commitAt(d.time)) {
    d.pin(d.time, DynamicState{*unit, d.current_B.w_B});  // cannot happen: the step succeeded
    return;
  }
  // Only the orientation: q_WP = q_WB (x) q_BP; w_P and M_P (the body's own state) stay.
  d.knot.q_WP = *unit * d.config.body.q_BP();
  d.stuck = false;
  d.setCurrent(d.knot_time, d.knot);
}

bool DynamicPropagator::anchored() const { return impl_->anchored; }
double DynamicPropagator::time() const { return impl_->time; }
const DynamicState& DynamicPropagator::state() const { return impl_->current_B; }
std::uint64_t DynamicPropagator::steps() const { return impl_->steps; }
std::uint64_t DynamicPropagator::failedSteps() const { return impl_->failed_steps; }
StepStatus DynamicPropagator::lastFailure() const { return impl_->last_failure; }
std::size_t DynamicPropagator::stateBytes() { return sizeof(Impl); }
std::uint64_t DynamicPropagator::lastCallWork() const { return impl_->work; }
double DynamicPropagator::normError() const { return impl_->norm_error; }

double DynamicPropagator::kineticEnergy() const {
  return impl_->config.body.kineticEnergy(impl_->current_B.w_B);
}

Eigen::Vector3d DynamicPropagator::angularMomentum_B() const {
  return impl_->config.body.angularMomentum_B(impl_->current_B.w_B);
}

double DynamicPropagator::energyDrift() const {
  const double e0 = impl_->energy0;
  const double e = kineticEnergy();
  return e0 > 0.0 ? (e - e0) / e0 : e;
}

double DynamicPropagator::momentumDrift() const {
  const double m0 = impl_->momentum0;
  const double m = angularMomentum_B().norm();
  return m0 > 0.0 ? (m - m0) / m0 : m;
}

}  // namespace attitude_propagator
