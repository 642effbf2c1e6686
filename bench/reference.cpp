#include "reference.h"

#include <array>
#include <cmath>

#include <boost/numeric/odeint.hpp>

#include "attitude_propagator/numerics/quaternion.h"

namespace bench {

namespace {

namespace odeint = boost::numeric::odeint;
// Long double (64-bit mantissa): the reference must be far tighter than the 1e-12 rad the
// exact solution is judged at, and double round-off over 1e5 steps would not be.
using Real = long double;
using OdeState = std::array<Real, 7>;  // q (w, x, y, z), w_B (x, y, z)

constexpr Real kTolerance = 1e-16L;

/// dq/dt = 1/2 q (x) (0, w) = 1/2 (-v.w, q_w w + v x w),  I dw/dt = (I w) x w + T.
struct EulerEquations {
  std::array<Real, 3> I;
  std::array<Real, 3> tau;

  void operator()(const OdeState& x, OdeState& dxdt, Real /*t*/) const {
    const Real qw = x[0], vx = x[1], vy = x[2], vz = x[3];
    const Real wx = x[4], wy = x[5], wz = x[6];
    dxdt[0] = -0.5L * (vx * wx + vy * wy + vz * wz);
    dxdt[1] = 0.5L * (qw * wx + vy * wz - vz * wy);
    dxdt[2] = 0.5L * (qw * wy + vz * wx - vx * wz);
    dxdt[3] = 0.5L * (qw * wz + vx * wy - vy * wx);
    const Real Mx = I[0] * wx, My = I[1] * wy, Mz = I[2] * wz;
    dxdt[4] = (My * wz - Mz * wy + tau[0]) / I[0];
    dxdt[5] = (Mz * wx - Mx * wz + tau[1]) / I[1];
    dxdt[6] = (Mx * wy - My * wx + tau[2]) / I[2];
  }
};

OdeState pack(const ap::DynamicState& x) {
  return {x.q_WB.w(), x.q_WB.x(), x.q_WB.y(), x.q_WB.z(), x.w_B.x(), x.w_B.y(), x.w_B.z()};
}

ap::DynamicState unpack(const OdeState& s) {
  ap::DynamicState x;
  const Real n = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3]);
  x.q_WB = Eigen::Quaterniond(static_cast<double>(s[0] / n), static_cast<double>(s[1] / n),
                              static_cast<double>(s[2] / n), static_cast<double>(s[3] / n));
  x.w_B = Eigen::Vector3d(static_cast<double>(s[4]), static_cast<double>(s[5]),
                          static_cast<double>(s[6]));
  return x;
}

std::array<Real, 3> toReal(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

std::vector<ap::DynamicState> referenceStates(const Eigen::Vector3d& moments,
                                              const ap::DynamicState& x0,
                                              const Eigen::Vector3d& tau_B,
                                              const std::vector<double>& times) {
  odeint::bulirsch_stoer<OdeState, Real> stepper(kTolerance, kTolerance);
  const EulerEquations system{toReal(moments), toReal(tau_B)};
  OdeState state = pack(x0);
  std::vector<ap::DynamicState> out;
  Real t = 0.0L;
  for (double target : times) {
    if (target > t) {
      odeint::integrate_adaptive(stepper, system, state, t, static_cast<Real>(target), 1e-3L);
      t = target;
    }
    out.push_back(unpack(state));
  }
  return out;
}

double referenceSelfCheck() {
  const Eigen::Vector3d I(3.0, 2.0, 1.5);
  const Eigen::Vector3d tau(0.0, 0.0, 0.2);  // along principal axis 3, from rest
  std::vector<double> times;
  for (int k = 1; k <= 10; ++k) times.push_back(k);
  const auto states = referenceStates(I, ap::DynamicState{}, tau, times);
  double worst = 0.0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    const double angle = tau.z() * t * t / (2.0 * I.z());
    const Eigen::Quaterniond truth(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
    worst = std::max(worst, ap::rotationAngle(states[i].q_WB, truth));
  }
  return worst;
}

}  // namespace bench
