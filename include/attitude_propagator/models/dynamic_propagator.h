// Stateful dynamic propagation (docs/design.md §4): Euler equations I dw/dt = (I w) x w + T with
// the kinematics dq/dt = 1/2 q (x) (0, w) (Coutsias–Romero eqs. 9 and 10), driven by held torques
// or torque-free, with the time policy of docs/design.md §6.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/rigid_body.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

struct DynamicConfig {
  RigidBody body = RigidBody::fromPrincipalMoments(Eigen::Vector3d::Ones());
  /// Auto: Exact when !torque_input (sphere, symmetric top or triaxial, the cheapest exact
  /// form), otherwise Rk4.
  Integrator integrator = Integrator::Auto;
  bool torque_input = false;
  /// Fixed grid step (s). The state at a stamp t is the grid state at the last grid point
  /// before t advanced by one partial step to t, so it does not depend on how the caller's
  /// clock reached t.
  double max_step = 0.01;
  double tolerance = 1e-9;      ///< dopri5 absolute and relative tolerance
  double torque_timeout = 0.0;  ///< s; a torque older than this counts as zero (0: held forever)
  TimePolicy time_policy;
  /// |w_B| at most kMaxBodyRate; the quaternion is normalised at any finite scale.
  DynamicState initial;
  /// Integrator work one call (advanceTo, setTorque, setRate) may spend: one unit per fixed
  /// step or exact evaluation, one per trial sub-step of dopri5. A call that needs more
  /// returns FailedStep, so every call runs in bounded time. Must cover the fixed steps of
  /// the longest interval, max_dt / max_step + kBudgetHeadroomSteps.
  std::uint64_t step_budget = kDefaultStepBudget;
};

/// Steps a call may need besides max_dt / max_step grid steps: the partial step to the stamp,
/// a torque's expiry, a late input's knot and the re-integration after it.
constexpr double kBudgetHeadroomSteps = 8.0;

class DynamicPropagator {
 public:
  /// Throws std::invalid_argument naming the problem (an integrator that is not dynamic,
  /// `exact` with torque input, non-positive max_step or tolerance, a step_budget below
  /// max_dt / max_step + kBudgetHeadroomSteps, a non-finite or zero initial quaternion, an
  /// initial rate above kMaxBodyRate, or one the exact motion cannot be evaluated from).
  explicit DynamicPropagator(const DynamicConfig& config);
  ~DynamicPropagator();
  DynamicPropagator(DynamicPropagator&&) noexcept;
  DynamicPropagator& operator=(DynamicPropagator&&) noexcept;
  /// A copy is the whole state (knots, held torque, counters): the fix history keeps one per
  /// step to replay from (docs/design.md §6.9). Assigning to an existing one allocates nothing.
  DynamicPropagator(const DynamicPropagator& other);
  DynamicPropagator& operator=(const DynamicPropagator& other);

  /// The integrator in use after resolving Auto.
  Integrator integrator() const;
  /// Which model runs: "exact_sphere", "exact_symmetric_top", "exact_triaxial", or
  /// "numerical_<integrator name>". Logged at start and reported in AttitudeState.
  std::string modelName() const;

  /// Advances the state to time t under docs/design.md §6: the first call anchors (the state at t
  /// is the initial one), stamps at or before time() do nothing (DroppedStale; going back in time
  /// is the engine's decision: reset()), gaps over max_dt hold the state. Never throws: if the
  /// integrator cannot complete the interval (see StampOutcome::FailedStep and lastFailure()) the
  /// state at time() is held and re-anchored at t.
  StampOutcome advanceTo(double t);

  /// Torque tau (N m) from time t on, in the body or the fixed frame (T_B = Q^T t_W, notes
  /// eq. 10), held until the next sample (or for torque_timeout). Advances to t first.
  /// Non-finite input is RejectedNonFinite, |tau| > kMaxTorque RejectedOutOfRange (state
  /// unchanged); FailedStep as for advanceTo (the torque then acts from the new anchor). A sample
  /// stamped at or before time() (it arrived after the clock passed its stamp) acts from its stamp
  /// if no grid point was committed since, else from the last grid point, and returns Advanced.
  /// Samples come in their source's order: the engine drops one not newer than the previous
  /// (SourceTimeline, docs/design.md §6.5), the one owner of that rule. With the exact model a
  /// non-zero torque throws std::logic_error.
  StampOutcome setTorque(double t, const Eigen::Vector3d& tau, TorqueFrame frame);

  /// A measured body rate at t: advances to t, then sets w_B (the orientation is kept). Late
  /// samples are placed as for setTorque. |w_B| > kMaxBodyRate is RejectedOutOfRange.
  StampOutcome setRate(double t, const Eigen::Vector3d& w_B);

  /// Pins the state at time t (a new anchor); the quaternion is normalised at any finite
  /// scale. Throws std::invalid_argument, leaving the propagator unchanged, on a non-finite
  /// stamp or value, a zero quaternion, |w_B| > kMaxBodyRate, or (exact model) a state the
  /// closed form cannot be evaluated from.
  void setState(double t, const DynamicState& state);

  /// Back to the initial state, waiting for an anchoring stamp.
  void reset();

  /// Replaces the orientation at time() (an absolute fix, docs/design.md §6.9): the state at
  /// time() becomes a knot and its orientation q_WB; the angular velocity (and momentum), the
  /// grid and the held torque stay, so the steps that follow are the ones that would have
  /// followed from the corrected state. No-op before the anchor or for a zero or non-finite q
  /// (normalised otherwise).
  void correctOrientation(const Eigen::Quaterniond& q_WB);

  bool anchored() const;
  double time() const;
  /// State at time(), in the user's body frame.
  const DynamicState& state() const;
  std::uint64_t steps() const;
  /// |q| - 1 before the last renormalisation.
  double normError() const;
  double kineticEnergy() const;
  Eigen::Vector3d angularMomentum_B() const;
  /// Relative drift of the energy and of |M| since the anchor (zero by construction for
  /// `exact`; meaningful only without torque).
  double energyDrift() const;
  double momentumDrift() const;
  /// Calls that returned FailedStep (each held the state and re-anchored).
  std::uint64_t failedSteps() const;
  /// Why the last FailedStep happened (StepStatus::Ok before the first one).
  StepStatus lastFailure() const;
  /// Bytes a copy holds beyond sizeof(DynamicPropagator) (its state, on the heap).
  static std::size_t stateBytes();
  /// Work units (as for step_budget) the last advanceTo, setTorque or setRate spent.
  std::uint64_t lastCallWork() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace attitude_propagator
