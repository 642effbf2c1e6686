// One step of the dynamic model (docs/design.md §4, docs/numerics.md §5): the Euler equations with
// torque and the kinematics,
//   I dw/dt = (I w) x w + T,   dq/dt = 1/2 q (x) (0, w)          (Coutsias–Romero eqs. 10 and 9),
// integrated together on the state (q, w) by one of the dynamic integrators.
//
// All methods work in the principal frame P of the body, where I is diagonal and the Euler
// equations read I1 dw1/dt = (I2 - I3) w2 w3 + T1 and cyclic. DynamicStepper converts to and
// from the user's body frame B at the edges; callers that step many times (the propagator,
// the benchmarks) may keep a PrincipalState and call stepPrincipal() directly, which does not
// allocate.
#pragma once

#include <cstdint>
#include <memory>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/rigid_body.h"

namespace attitude_propagator {

class TorqueFreeMotion;

/// The state in the principal frame: x_W = q_WP x_P, w_P = q_BP^c w_B.
struct PrincipalState {
  Eigen::Quaterniond q_WP = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero();
  /// The angular momentum M_P = I w_P as the splittings carry it from step to step. Rounding
  /// it through the rate each step, M -> w = M / I -> M = I w, biases |M| (measured on the HLW
  /// body, docs/numerics.md §8, 10^5 steps of 0.1: relative |M| drift 2.4e-12 with the round trip,
  /// 4e-14 without). A stepper uses M_P only while it is consistent with w_P, i.e. while
  /// w_P == M_P / I exactly as a splitting step leaves them; otherwise (w_P written by the
  /// caller or by another method) it starts from I w_P, so callers may ignore this member.
  Eigen::Vector3d M_P = Eigen::Vector3d::Zero();
};

/// A torque held over a step, as the integrators see it: tau_P in P for a body torque, or
/// t_W for a fixed-frame torque whose principal components T_P = Q_WP^T t_W follow the
/// attitude (notes eq. 10).
struct PrincipalTorque {
  Eigen::Vector3d tau = Eigen::Vector3d::Zero();
  bool fixed = false;

  bool isZero() const { return tau.isZero(0.0); }
  /// Torque in P at attitude q_WP (which must be of unit length to round-off).
  Eigen::Vector3d inP(const Eigen::Quaterniond& q_WP) const {
    return fixed ? Eigen::Vector3d(q_WP.conjugate() * tau) : tau;
  }
};

/// What a step reports besides the new state.
struct StepInfo {
  /// |q| - 1 before renormalisation (rk4, dopri5: the drift off the unit sphere; the
  /// Lie-group steps of implicit_midpoint, splitting and exact stay unit to round-off).
  double norm_error = 0.0;
  /// implicit_midpoint: fixed-point iterations; dopri5: accepted sub-steps; others: 1.
  int iterations = 0;
  /// dopri5: rejected trial steps.
  int rejected = 0;
  /// Work done, in the units of a step budget: dopri5's trial sub-steps (accepted and
  /// rejected); 1 for the other methods, whose cost per step is bounded.
  std::uint64_t attempts = 0;
};

/// Why tryStepPrincipal() did not commit a step.
enum class StepStatus {
  Ok,
  NonFinite,        ///< the result left the finite numbers, the unit sphere or kMaxStateRate
  OverBudget,       ///< dopri5 needed more trial sub-steps than the budget allowed
  NoConvergence,    ///< dopri5's step size collapsed below one ulp of the interval
  EvaluationError,  ///< the closed form threw (Boost.Math evaluation error, torque on exact)
};

const char* stepStatusName(StepStatus status);

/// Whether a stepped state may be committed: finite, q of unit length to sqrt(eps),
/// |w_P| <= kMaxStateRate (limits.h).
bool committable(const PrincipalState& x);

/// A dynamic integrator bound to a body: a stepper with a declared order, as the tests measure it.
///
/// - rk4: classical Runge-Kutta on (q, w), q renormalised after the step. Order 4.
/// - implicit_midpoint: y1 = y0 + h f((y0 + y1)/2), solved by fixed-point iteration on the
///   midpoint rate to round-off. The quaternion part is then the Cayley transform
///   q1 = q0 (x) (1 + a)/(1 - a), a = (h/4)(0, w_mid), so |q| stays 1. Keeps the energy and
///   |M| of a free body to round-off (quadratic invariants). Order 2.
/// - splitting: Strang splitting of T = sum M_i^2/(2 I_i) into three exact rotations about the
///   principal axes, ordered smallest-largest-middle-largest-smallest so the middle axis sits
///   in the centre (the 1-3-2-3-1 scheme of Fasso 2003, the most accurate ordering), with a
///   torque as half kicks M += (h/2) T around the free flow. |M| exact without torque,
///   energy bounded; exact for a torque along a principal axis from rest. Order 2.
/// - splitting4: Yoshida's triple jump S(w1 h) S(w0 h) S(w1 h) of `splitting`,
///   w1 = 1/(2 - 2^(1/3)), w0 = -2^(1/3) w1. Order 4.
/// - dopri5: Boost.Odeint runge_kutta_dopri5 in a controlled stepper with absolute and
///   relative tolerance `tolerance`, crossing h in as many accepted sub-steps as it needs; q
///   renormalised after each accepted sub-step.
/// - exact: the torque-free motion (torque_free_motion.h) evaluated at h; throws
///   std::invalid_argument if the torque is not zero. The closed form is cached: stepping
///   again from the state it was built through, or from the last state it produced, evaluates
///   the same motion (the time along it summed without rounding drift); any other state
///   builds the motion through that state.
///
/// A stepper is cheap to copy (copies share the cached closed form, which never changes) and
/// not thread-safe (dopri5 keeps its step-size suggestion, exact its closed form).
class DynamicStepper {
 public:
  /// Throws std::invalid_argument for an integrator that is not dynamic (or Auto) and for a
  /// non-positive or non-finite tolerance.
  DynamicStepper(Integrator method, const RigidBody& body, double tolerance = 1e-9);

  Integrator method() const { return method_; }
  /// declaredOrder(method, Model::Dynamic): 4, 2, 2, 4, 0 (adaptive), 0 (exact).
  int order() const;
  const RigidBody& body() const { return body_; }

  PrincipalState toPrincipal(const DynamicState& x_B) const;
  DynamicState fromPrincipal(const PrincipalState& x_P) const;
  PrincipalTorque toPrincipal(const TorqueInput& torque) const;

  /// Advances x by h (which may be zero or negative for the explicit and symmetric methods),
  /// in place, in the principal frame. Throws std::runtime_error when dopri5's step-size
  /// control fails (10^4 rejected trials or a collapsed step size) and lets the closed form's
  /// exceptions through; callers that must not throw use tryStepPrincipal().
  void stepPrincipal(PrincipalState& x, const PrincipalTorque& torque, double h,
                     StepInfo* info = nullptr) const;

  /// The same step, never throwing and never committing a bad result: x is changed only when
  /// the status is Ok, i.e. the result is finite, q of unit length (to sqrt(eps)) and
  /// |w| <= kMaxStateRate. dopri5 gives up after `budget` trial sub-steps (or when its step
  /// size collapses); the other methods need one unit. info->attempts reports the work done,
  /// also on failure.
  StepStatus tryStepPrincipal(PrincipalState& x, const PrincipalTorque& torque, double h,
                              std::uint64_t budget, StepInfo* info = nullptr) const noexcept;

  /// dopri5's step-size suggestion carried from one call to the next (0: start with h). A
  /// caller that needs results independent of its call history (DynamicPropagator) saves it
  /// with its committed states and restores it before stepping from them.
  double stepSizeHint() const { return dopri5_dt_; }
  void setStepSizeHint(double dt) const { dopri5_dt_ = dt; }

  /// Same, in the user's body frame.
  DynamicState step(const DynamicState& x, const TorqueInput& torque, double h,
                    StepInfo* info = nullptr) const;

  // The methods' step functions (DynamicStepFunction, integrator.h), which the integrator
  // table points to: x advanced by h in place. The fixed-cost methods leave the one iteration
  // and one attempt the caller reported and return Ok; dopri5 stops at `budget` trial
  // sub-steps. Call them through stepPrincipal() or tryStepPrincipal().
  StepStatus rk4(PrincipalState& x, const PrincipalTorque& torque, double h, std::uint64_t budget,
                 StepInfo& info) const;
  StepStatus implicitMidpoint(PrincipalState& x, const PrincipalTorque& torque, double h,
                              std::uint64_t budget, StepInfo& info) const;
  StepStatus splitting(PrincipalState& x, const PrincipalTorque& torque, double h,
                       std::uint64_t budget, StepInfo& info) const;
  StepStatus splitting4(PrincipalState& x, const PrincipalTorque& torque, double h,
                        std::uint64_t budget, StepInfo& info) const;
  /// Dormand-Prince across h in at most `budget` trial sub-steps; x is left partly advanced
  /// on failure.
  StepStatus dopri5(PrincipalState& x, const PrincipalTorque& torque, double h,
                    std::uint64_t budget, StepInfo& info) const;
  StepStatus exact(PrincipalState& x, const PrincipalTorque& torque, double h, std::uint64_t budget,
                   StepInfo& info) const;

 private:
  /// The angular momentum of x: x.M_P if consistent with x.w_P, else I x.w_P.
  Eigen::Vector3d momentum(const PrincipalState& x) const;
  void strang(Eigen::Quaterniond& q_WP, Eigen::Vector3d& M_P, const PrincipalTorque& torque,
              double h) const;
  /// The splittings flow M, not w: x takes the M they carried, and w = M / I read off.
  void setMomentum(PrincipalState& x, const Eigen::Vector3d& M, StepInfo& info) const;

  /// exact: the closed form through `origin`, and the last state it produced at time
  /// `last_time` + `last_time_low` along it (a compensated sum of the steps).
  struct ClosedForm {
    std::shared_ptr<const TorqueFreeMotion> motion;
    PrincipalState origin;
    PrincipalState last;
    double last_time = 0.0;
    double last_time_low = 0.0;
  };

  Integrator method_;
  RigidBody body_;
  RigidBody principal_body_;  // the same body with B = P, for the exact solution
  Eigen::Vector3d I_P_;
  Eigen::Vector3d I_inv_P_;
  int axis_small_, axis_middle_, axis_large_;
  double tolerance_;
  DynamicStepFunction step_;
  mutable double dopri5_dt_ = 0.0;  // last suggested sub-step, 0 before the first step
  mutable ClosedForm closed_form_;
};

/// One step of `method` from x (user's body frame) with the torque held over h. Builds a
/// DynamicStepper each call; prefer a stepper for repeated steps.
DynamicState dynamicStep(Integrator method, const RigidBody& body, const DynamicState& x,
                         const TorqueInput& torque, double h, StepInfo* info = nullptr,
                         double tolerance = 1e-9);

}  // namespace attitude_propagator
