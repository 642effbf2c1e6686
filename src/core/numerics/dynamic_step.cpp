#include "attitude_propagator/numerics/dynamic_step.h"

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <boost/numeric/odeint/stepper/controlled_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/generation.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/torque_free_motion.h"

namespace attitude_propagator {

namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// The implicit midpoint iteration converges in 8-11 iterations at h = 0.1 on the free body
// (docs/numerics.md §5); the cap only stops a step that is too large to contract.
constexpr int kMaxMidpointIterations = 100;
// Yoshida's triple jump: w1 = 1/(2 - 2^(1/3)), w0 = -2^(1/3) w1 (no std::pow at run time).
constexpr double kCubeRootOfTwo = 1.2599210498948731647672106;
constexpr double kYoshidaW1 = 1.0 / (2.0 - kCubeRootOfTwo);
constexpr double kYoshidaW0 = -kCubeRootOfTwo * kYoshidaW1;
// dopri5 gives up (rather than loop forever) after this many rejected trials in one step.
constexpr int kMaxRejectedSubsteps = 10000;
// A committed quaternion is of unit length to round-off; sqrt(eps) leaves room for the
// rounding of denormal components and catches any step that broke.
const double kUnitTolerance = std::sqrt(kEpsilon);

/// 1/2 q (x) (0, w) (notes eq. 9), for any q (RK stages are not exactly unit).
Eigen::Quaterniond halfProductWithRate(const Eigen::Quaterniond& q, const Eigen::Vector3d& w) {
  const Eigen::Vector3d v = q.vec();
  const Eigen::Vector3d r = 0.5 * (q.w() * w + v.cross(w));
  return Eigen::Quaterniond(-0.5 * v.dot(w), r.x(), r.y(), r.z());
}

/// The Euler equations (notes eq. 10) in P: dw/dt = I^-1 ((I w) x w + T). Forced inline:
/// GCC -O3 kept it out of line and the implicit midpoint step went from 55 to 103 ns.
EIGEN_STRONG_INLINE Eigen::Vector3d angularAcceleration(const Eigen::Vector3d& I,
                                                        const Eigen::Vector3d& I_inv,
                                                        const Eigen::Vector3d& w,
                                                        const Eigen::Vector3d& tau) {
  return I_inv.cwiseProduct(Eigen::Vector3d(I.cwiseProduct(w)).cross(w) + tau);
}

/// q + s d, coefficient-wise.
Eigen::Quaterniond axpy(const Eigen::Quaterniond& q, double s, const Eigen::Quaterniond& d) {
  Eigen::Quaterniond r;
  r.coeffs() = q.coeffs() + s * d.coeffs();
  return r;
}

/// The torque in P at attitude q, for a q that is not exactly unit (RK stages are off the
/// unit sphere by O(h^2)): a fixed-frame torque is rotated by q/|q|, R^T t = t + (2/|q|^2)
/// (v x (v x t) - w (v x t)) for q = (w, v), so a torque along a principal axis stays
/// exactly along it.
Eigen::Vector3d torqueAt(const PrincipalTorque& torque, const Eigen::Quaterniond& q) {
  if (!torque.fixed) return torque.tau;
  const Eigen::Vector3d v = q.vec();
  const Eigen::Vector3d vt = v.cross(torque.tau);
  const double s = 2.0 / q.squaredNorm();
  return torque.tau + s * (v.cross(vt) - q.w() * vt);
}

double normaliseAndReport(Eigen::Quaterniond& q) {
  const double norm = q.norm();
  q.coeffs() /= norm;
  return norm - 1.0;
}

/// The exact flow of H_i = M_i^2 / (2 I_i) over tau: the body turns about principal axis i
/// at the constant rate w_i = M_i / I_i, so q <- q (x) Exp(theta e_i) with theta = tau w_i,
/// and M turns the other way in the body, M <- R_i(-theta) M (dM/dt = M x w_i e_i).
void axisRotation(int i, double tau, const Eigen::Vector3d& I_inv, Eigen::Quaterniond& q,
                  Eigen::Vector3d& M) {
  const int j = (i + 1) % 3;
  const int k = (i + 2) % 3;
  const double half = 0.5 * tau * M[i] * I_inv[i];
  const double s2 = std::sin(half);
  const double c2 = std::cos(half);
  // One sin/cos pair of the half angle serves the quaternion and M. The rotation of M must
  // keep c^2 + s^2 = 1 without bias, since its error accumulates in |M| over every sub-flow:
  // with c = 1 - 2 s2^2, s = 2 s2 c2, c^2 + s^2 - 1 = 4 s2^2 (c2^2 + s2^2 - 1), the round-off
  // of sin and cos scaled down by sin^2(theta/2). The textbook c = c2^2 - s2^2 carries
  // 2 (c2^2 + s2^2 - 1) in full, and its small bias drifted |M| by 1.7e-13 in 10^5 splitting4
  // steps of the HLW body (6e-14 with this form, the random walk of rounding M).
  const double c = 1.0 - 2.0 * s2 * s2;
  const double s = 2.0 * s2 * c2;
  const double Mj = M[j];
  const double Mk = M[k];
  M[j] = c * Mj + s * Mk;
  M[k] = c * Mk - s * Mj;
  // q (x) (c2, s2 e_i) = (w c2 - s2 v_i, c2 v + s2 w e_i + s2 v x e_i), (v x e_i) = v_k e_j -
  // v_j e_k.
  const double w = q.w();
  Eigen::Vector3d v = q.vec();
  const double vi = v[i];
  const double vj = v[j];
  const double vk = v[k];
  v[i] = c2 * vi + s2 * w;
  v[j] = c2 * vj + s2 * vk;
  v[k] = c2 * vk - s2 * vj;
  q.w() = w * c2 - s2 * vi;
  q.vec() = v;
}

// ---- dopri5 through Boost.Odeint on a fixed-size state (no heap) -------------------------
using OdeState = std::array<double, 7>;  // q (w, x, y, z), w_P (x, y, z)

struct EulerSystem {
  Eigen::Vector3d I;
  Eigen::Vector3d I_inv;
  PrincipalTorque torque;

  void operator()(const OdeState& x, OdeState& dxdt, double /*t*/) const {
    const Eigen::Quaterniond q(x[0], x[1], x[2], x[3]);
    const Eigen::Vector3d w(x[4], x[5], x[6]);
    const Eigen::Quaterniond dq = halfProductWithRate(q, w);
    const Eigen::Vector3d dw = angularAcceleration(I, I_inv, w, torqueAt(torque, q));
    dxdt = {dq.w(), dq.x(), dq.y(), dq.z(), dw.x(), dw.y(), dw.z()};
  }
};

}  // namespace

const char* stepStatusName(StepStatus status) {
  switch (status) {
    case StepStatus::Ok:
      return "ok";
    case StepStatus::NonFinite:
      return "non_finite";
    case StepStatus::OverBudget:
      return "over_budget";
    case StepStatus::NoConvergence:
      return "no_convergence";
    case StepStatus::EvaluationError:
      return "evaluation_error";
  }
  return "unknown";
}

DynamicStepper::DynamicStepper(Integrator method, const RigidBody& body, double tolerance)
    : method_(method),
      body_(body),
      principal_body_(RigidBody::fromPrincipalMoments(body.principalMoments(),
                                                      RigidBody::TriangleInequality::Ignore)),
      I_P_(body.principalMoments()),
      I_inv_P_(body.inverseMoments()),
      tolerance_(tolerance),
      step_(integratorInfo(method).dynamic_step) {
  if (step_ == nullptr) {
    throw std::invalid_argument("integrator: '" + integratorName(method) +
                                "' cannot step the dynamic model; accepted: " +
                                joinNames(integratorNames(integratorsFor(Model::Dynamic))));
  }
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    throw std::invalid_argument("tolerance: must be positive and finite, got " +
                                std::to_string(tolerance));
  }
  const std::array<int, 3> sorted = body.sortedAxes();
  axis_small_ = sorted[0];
  axis_middle_ = sorted[1];
  axis_large_ = sorted[2];
}

int DynamicStepper::order() const { return declaredOrder(method_, Model::Dynamic); }

PrincipalState DynamicStepper::toPrincipal(const DynamicState& x_B) const {
  PrincipalState x;
  x.q_WP = x_B.q_WB * body_.q_BP();
  x.w_P = body_.q_BP().conjugate() * x_B.w_B;
  x.M_P = I_P_.cwiseProduct(x.w_P);
  return x;
}

DynamicState DynamicStepper::fromPrincipal(const PrincipalState& x_P) const {
  DynamicState x;
  x.q_WB = x_P.q_WP * body_.q_BP().conjugate();
  x.w_B = body_.q_BP() * x_P.w_P;
  return x;
}

PrincipalTorque DynamicStepper::toPrincipal(const TorqueInput& torque) const {
  PrincipalTorque t;
  t.fixed = torque.frame == TorqueFrame::Fixed;
  t.tau = t.fixed ? torque.tau : Eigen::Vector3d(body_.q_BP().conjugate() * torque.tau);
  return t;
}

void DynamicStepper::stepPrincipal(PrincipalState& x, const PrincipalTorque& torque, double h,
                                   StepInfo* info) const {
  StepInfo local;
  StepInfo& report = info ? *info : local;
  report = StepInfo{};
  report.iterations = 1;
  report.attempts = 1;
  const StepStatus status = (this->*step_)(x, torque, h, UINT64_MAX, report);
  if (status != StepStatus::Ok) {
    throw std::runtime_error(integratorName(method_) + ": step size control failed (" +
                             stepStatusName(status) + ")");
  }
}

StepStatus DynamicStepper::tryStepPrincipal(PrincipalState& x, const PrincipalTorque& torque,
                                            double h, std::uint64_t budget,
                                            StepInfo* info) const noexcept {
  StepInfo local;
  StepInfo& report = info ? *info : local;
  report = StepInfo{};
  if (budget == 0) return StepStatus::OverBudget;
  report.iterations = 1;
  report.attempts = 1;
  PrincipalState y = x;
  StepStatus status = StepStatus::Ok;
  try {
    status = (this->*step_)(y, torque, h, budget, report);
  } catch (...) {  // Boost.Math's evaluation and domain errors in the closed form, or a torque
    status = StepStatus::EvaluationError;
  }
  if (status == StepStatus::Ok && !committable(y)) status = StepStatus::NonFinite;
  if (status == StepStatus::Ok) x = y;
  return status;
}

bool committable(const PrincipalState& x) {
  return x.q_WP.coeffs().allFinite() && x.w_P.allFinite() && x.M_P.allFinite() &&
         std::abs(x.q_WP.squaredNorm() - 1.0) <= kUnitTolerance && x.w_P.norm() <= kMaxStateRate;
}

StepStatus DynamicStepper::splitting(PrincipalState& x, const PrincipalTorque& torque, double h,
                                     std::uint64_t /*budget*/, StepInfo& info) const {
  Eigen::Vector3d M = momentum(x);
  strang(x.q_WP, M, torque, h);
  setMomentum(x, M, info);
  return StepStatus::Ok;
}

StepStatus DynamicStepper::splitting4(PrincipalState& x, const PrincipalTorque& torque, double h,
                                      std::uint64_t /*budget*/, StepInfo& info) const {
  Eigen::Vector3d M = momentum(x);
  strang(x.q_WP, M, torque, kYoshidaW1 * h);
  strang(x.q_WP, M, torque, kYoshidaW0 * h);
  strang(x.q_WP, M, torque, kYoshidaW1 * h);
  setMomentum(x, M, info);
  return StepStatus::Ok;
}

// The splittings flow M, not w: M is carried through the sub-flows and from step to step
// (PrincipalState::M_P), and w = M / I is only read off.
void DynamicStepper::setMomentum(PrincipalState& x, const Eigen::Vector3d& M,
                                 StepInfo& info) const {
  // M / I, not M * (1/I), so that momentum() recognises the pair as consistent.
  x.w_P = M.cwiseQuotient(I_P_);
  x.M_P = M;
  info.norm_error = normaliseAndReport(x.q_WP);
}

DynamicState DynamicStepper::step(const DynamicState& x, const TorqueInput& torque, double h,
                                  StepInfo* info) const {
  PrincipalState x_P = toPrincipal(x);
  stepPrincipal(x_P, toPrincipal(torque), h, info);
  return fromPrincipal(x_P);
}

// Classical RK4 on y = (q, w), f(y) = (1/2 q (x) (0, w), I^-1 ((I w) x w + T(q))).
StepStatus DynamicStepper::rk4(PrincipalState& x, const PrincipalTorque& torque, double h,
                               std::uint64_t /*budget*/, StepInfo& info) const {
  const Eigen::Quaterniond q0 = x.q_WP;
  const Eigen::Vector3d w0 = x.w_P;
  const double h2 = 0.5 * h;

  const Eigen::Quaterniond kq1 = halfProductWithRate(q0, w0);
  const Eigen::Vector3d kw1 = angularAcceleration(I_P_, I_inv_P_, w0, torqueAt(torque, q0));

  const Eigen::Quaterniond q2 = axpy(q0, h2, kq1);
  const Eigen::Vector3d w2 = w0 + h2 * kw1;
  const Eigen::Quaterniond kq2 = halfProductWithRate(q2, w2);
  const Eigen::Vector3d kw2 = angularAcceleration(I_P_, I_inv_P_, w2, torqueAt(torque, q2));

  const Eigen::Quaterniond q3 = axpy(q0, h2, kq2);
  const Eigen::Vector3d w3 = w0 + h2 * kw2;
  const Eigen::Quaterniond kq3 = halfProductWithRate(q3, w3);
  const Eigen::Vector3d kw3 = angularAcceleration(I_P_, I_inv_P_, w3, torqueAt(torque, q3));

  const Eigen::Quaterniond q4 = axpy(q0, h, kq3);
  const Eigen::Vector3d w4 = w0 + h * kw3;
  const Eigen::Quaterniond kq4 = halfProductWithRate(q4, w4);
  const Eigen::Vector3d kw4 = angularAcceleration(I_P_, I_inv_P_, w4, torqueAt(torque, q4));

  const double h6 = h / 6.0;
  x.q_WP.coeffs() =
      q0.coeffs() + h6 * (kq1.coeffs() + 2.0 * (kq2.coeffs() + kq3.coeffs()) + kq4.coeffs());
  x.w_P = w0 + h6 * (kw1 + 2.0 * (kw2 + kw3) + kw4);
  info.norm_error = normaliseAndReport(x.q_WP);
  return StepStatus::Ok;
}

// Implicit midpoint on (q, w): w1 = w0 + h I^-1((I wm) x wm + T(qm)) with wm = (w0 + w1)/2,
// q1 = q0 + h/2 qm (x) (0, wm) with qm = (q0 + q1)/2. For a given wm the quaternion equation
// is linear, q1 (1 - a) = q0 (1 + a) with a = (h/4)(0, wm), solved by the Cayley transform
// q1 = q0 (x) ((1 - |a|^2) + 2a)/(1 + |a|^2); and qm is along q0 (x) (1 + a). So the
// iteration runs on wm alone (qm follows it only for a fixed-frame torque).
StepStatus DynamicStepper::implicitMidpoint(PrincipalState& x, const PrincipalTorque& torque,
                                            double h, std::uint64_t /*budget*/,
                                            StepInfo& info) const {
  const Eigen::Quaterniond q0 = x.q_WP;
  const Eigen::Vector3d w0 = x.w_P;
  const double h2 = 0.5 * h;
  const double h4 = 0.25 * h;
  const bool torqued = !torque.isZero();
  Eigen::Vector3d tau = torque.inP(q0);
  Eigen::Vector3d wm = w0;
  double previous = std::numeric_limits<double>::infinity();
  int iterations = 0;
  while (iterations < kMaxMidpointIterations) {
    ++iterations;
    if (torqued && torque.fixed) {
      const Eigen::Vector3d a = h4 * wm;
      const Eigen::Quaterniond qm =
          (q0 * Eigen::Quaterniond(1.0, a.x(), a.y(), a.z())).normalized();
      tau = torque.inP(qm);
    }
    const Eigen::Vector3d next = w0 + h2 * angularAcceleration(I_P_, I_inv_P_, wm, tau);
    const double change = (next - wm).cwiseAbs().maxCoeff();
    wm = next;
    // Converged when the update is below one ulp of the rate, or once it stops shrinking
    // (the round-off floor): the invariants then hold to round-off.
    if (change <= kEpsilon * wm.cwiseAbs().maxCoeff() || change >= previous) break;
    previous = change;
  }
  info.iterations = iterations;

  const Eigen::Vector3d a = h4 * wm;
  const double a2 = a.squaredNorm();
  const double scale = 1.0 / (1.0 + a2);
  const Eigen::Quaterniond cayley((1.0 - a2) * scale, 2.0 * scale * a.x(), 2.0 * scale * a.y(),
                                  2.0 * scale * a.z());
  x.q_WP = q0 * cayley;
  x.w_P = 2.0 * wm - w0;
  info.norm_error = normaliseAndReport(x.q_WP);
  return StepStatus::Ok;
}

Eigen::Vector3d DynamicStepper::momentum(const PrincipalState& x) const {
  return x.M_P.cwiseQuotient(I_P_) == x.w_P ? x.M_P : Eigen::Vector3d(I_P_.cwiseProduct(x.w_P));
}

// Strang splitting K(h/2) F(h) K(h/2) on (q, M): torque kicks M += (h/2) T(q) with q frozen
// (the exact flow of dM/dt = T(q), dq/dt = 0), around the free flow F(h) = R_s(h/2) R_l(h/2)
// R_m(h) R_l(h/2) R_s(h/2) (s, m, l: smallest, middle, largest moment).
void DynamicStepper::strang(Eigen::Quaterniond& q_WP, Eigen::Vector3d& M_P,
                            const PrincipalTorque& torque, double h) const {
  const double h2 = 0.5 * h;
  const bool torqued = !torque.isZero();
  if (torqued) M_P += h2 * torque.inP(q_WP);
  axisRotation(axis_small_, h2, I_inv_P_, q_WP, M_P);
  axisRotation(axis_large_, h2, I_inv_P_, q_WP, M_P);
  axisRotation(axis_middle_, h, I_inv_P_, q_WP, M_P);
  axisRotation(axis_large_, h2, I_inv_P_, q_WP, M_P);
  axisRotation(axis_small_, h2, I_inv_P_, q_WP, M_P);
  if (torqued) M_P += h2 * torque.inP(q_WP);
}

// Dormand-Prince 5(4) with step-size control across [0, h], driven trial by trial so that the
// work is counted and a failure is a status, not an exception or an endless loop; q
// renormalised after each accepted sub-step (and the FSAL derivative recomputed, since
// renormalising changed the state it belongs to).
StepStatus DynamicStepper::dopri5(PrincipalState& x, const PrincipalTorque& torque, double h,
                                  std::uint64_t budget, StepInfo& info) const {
  namespace odeint = boost::numeric::odeint;
  using Stepper = odeint::runge_kutta_dopri5<OdeState>;
  auto controlled = odeint::make_controlled(tolerance_, tolerance_, Stepper());
  const EulerSystem system{I_P_, I_inv_P_, torque};
  OdeState y{x.q_WP.w(), x.q_WP.x(), x.q_WP.y(), x.q_WP.z(), x.w_P.x(), x.w_P.y(), x.w_P.z()};

  info.iterations = 0;
  info.attempts = 0;
  if (h == 0.0) return StepStatus::Ok;
  if (!std::isfinite(h)) return StepStatus::NonFinite;
  const double direction = h > 0.0 ? 1.0 : -1.0;
  // A sub-step below one ulp of the interval cannot move t: the control has collapsed (a
  // tolerance below round-off, or a right-hand side that left the doubles).
  const double smallest = kEpsilon * std::abs(h);
  double t = 0.0;
  double dt = dopri5_dt_ > 0.0 ? direction * std::min(dopri5_dt_, std::abs(h)) : h;
  double worst_norm_error = 0.0;
  while (t != h) {
    if (info.attempts >= budget) return StepStatus::OverBudget;
    ++info.attempts;
    const double remaining = h - t;
    const bool last = std::abs(dt) >= std::abs(remaining);
    double try_dt = last ? remaining : dt;
    // On success try_step advances t_try by the step taken and puts the suggested next step
    // in try_dt; on failure it only shrinks try_dt.
    double t_try = t;
    if (controlled.try_step(system, y, t_try, try_dt) == odeint::fail) {
      if (++info.rejected > kMaxRejectedSubsteps || !(std::abs(try_dt) > smallest)) {
        return StepStatus::NoConvergence;
      }
      dt = try_dt;
      continue;
    }
    // A NaN error estimate passes the controller's test (NaN > 1 is false): check the state.
    double norm = 0.0;
    for (int i = 0; i < 4; ++i) norm += y[i] * y[i];
    norm = std::sqrt(norm);
    for (double v : y) {
      if (!std::isfinite(v)) return StepStatus::NonFinite;
    }
    if (!(norm > 0.0) || !std::isfinite(norm)) return StepStatus::NonFinite;
    // A rate past kMaxStateRate cannot be committed at the end: stop now, not at the budget.
    if (y[4] * y[4] + y[5] * y[5] + y[6] * y[6] > kMaxStateRate * kMaxStateRate) {
      return StepStatus::NonFinite;
    }
    ++info.iterations;
    // Land exactly on h, whatever round-off the sub-steps carry.
    const double next = last ? h : t_try;
    if (next == t) return StepStatus::NoConvergence;
    t = next;
    // A last sub-step shortened to land on h says nothing about the step size to come.
    if (!last || std::abs(try_dt) > std::abs(dt)) dt = try_dt;
    if (!(std::abs(dt) > smallest) && t != h) return StepStatus::NoConvergence;
    // Hopeless within the budget even if the step grew tenfold from here: give up early, so a
    // failing interval costs little (the controller grows a step by 5x at most per sub-step).
    if (t != h &&
        std::abs(h - t) / std::abs(dt) > 10.0 * static_cast<double>(budget - info.attempts)) {
      return StepStatus::OverBudget;
    }
    for (int i = 0; i < 4; ++i) y[i] /= norm;
    if (std::abs(norm - 1.0) > std::abs(worst_norm_error)) worst_norm_error = norm - 1.0;
    controlled.reset();
  }
  dopri5_dt_ = std::abs(dt);
  info.norm_error = worst_norm_error;
  x.q_WP = Eigen::Quaterniond(y[0], y[1], y[2], y[3]);
  x.w_P = Eigen::Vector3d(y[4], y[5], y[6]);
  return StepStatus::Ok;
}

StepStatus DynamicStepper::exact(PrincipalState& x, const PrincipalTorque& torque, double h,
                                 std::uint64_t /*budget*/, StepInfo& /*info*/) const {
  if (!torque.isZero()) {
    throw std::invalid_argument(
        "integrator: 'exact' is the torque-free motion and cannot take a torque");
  }
  ClosedForm& c = closed_form_;
  auto same = [](const PrincipalState& a, const PrincipalState& b) {
    return a.q_WP.coeffs() == b.q_WP.coeffs() && a.w_P == b.w_P;
  };
  double start = 0.0;
  double start_low = 0.0;
  if (c.motion && same(x, c.last)) {
    start = c.last_time;
    start_low = c.last_time_low;
  } else if (!c.motion || !same(x, c.origin)) {
    c.motion.reset();  // a throwing construction leaves no stale motion behind
    c.motion =
        std::make_shared<const TorqueFreeMotion>(principal_body_, DynamicState{x.q_WP, x.w_P});
    c.origin = x;
    c.last = x;
    c.last_time = 0.0;
    c.last_time_low = 0.0;
  }
  // start + h summed exactly (Knuth's two-sum): a run of steps from the last state lands on
  // the time a single evaluation would use, with no drift of one rounding per step.
  const double time = start + h;
  const double h_part = time - start;
  const double low = start_low + ((start - (time - h_part)) + (h - h_part));
  const DynamicState y = c.motion->evaluate(time + low);
  x.q_WP = y.q_WB;
  x.w_P = y.w_B;
  c.last = x;
  c.last_time = time;
  c.last_time_low = low;
  return StepStatus::Ok;
}

DynamicState dynamicStep(Integrator method, const RigidBody& body, const DynamicState& x,
                         const TorqueInput& torque, double h, StepInfo* info, double tolerance) {
  const DynamicStepper stepper(method, body, tolerance);
  return stepper.step(x, torque, h, info);
}

}  // namespace attitude_propagator
