#include "attitude_propagator/kinematic_step.h"

#include <cmath>
#include <stdexcept>

#include "attitude_propagator/quaternion.h"

namespace attitude_propagator {

namespace {

// Gauss–Legendre nodes and the weights of the fourth-order commutator-free step
// (REFERENCE §2): c = 1/2 -+ sqrt(3)/6, alpha = 1/4 + sqrt(3)/6, beta = 1/4 - sqrt(3)/6.
constexpr double kSqrt3 = 1.7320508075688772935;
constexpr double kGauss1 = 0.5 - kSqrt3 / 6.0;
constexpr double kGauss2 = 0.5 + kSqrt3 / 6.0;
constexpr double kAlpha = 0.25 + kSqrt3 / 6.0;
constexpr double kBeta = 0.25 - kSqrt3 / 6.0;

// q (x) (0, w): the body-rate quaternion product of dq/dt = 1/2 q (x) (0, w) (notes eq. 9).
Eigen::Vector4d timesPure(const Eigen::Vector4d& q_xyzw, const Eigen::Vector3d& w) {
  const Eigen::Quaterniond q(q_xyzw);
  return (q * pureQuaternion(w)).coeffs();
}

Eigen::Quaterniond eulerStep(const Eigen::Quaterniond& q, const Eigen::Vector3d& w0, double h) {
  return Eigen::Quaterniond(q.coeffs() + (0.5 * h) * timesPure(q.coeffs(), w0));
}

// Classical RK4 on dq/dt = 1/2 q (x) (0, w(t)), w linear between the two samples.
Eigen::Quaterniond rk4Step(const Eigen::Quaterniond& q, const Eigen::Vector3d& w0,
                           const Eigen::Vector3d& w1, double h) {
  const Eigen::Vector3d w_mid = 0.5 * (w0 + w1);
  const Eigen::Vector4d& y = q.coeffs();
  const Eigen::Vector4d k1 = 0.5 * timesPure(y, w0);
  const Eigen::Vector4d k2 = 0.5 * timesPure(y + (0.5 * h) * k1, w_mid);
  const Eigen::Vector4d k3 = 0.5 * timesPure(y + (0.5 * h) * k2, w_mid);
  const Eigen::Vector4d k4 = 0.5 * timesPure(y + h * k3, w1);
  return Eigen::Quaterniond(y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4));
}

// Interpolated rates at the two Gauss points of interval i of the window.
Eigen::Quaterniond cf4Step(const Eigen::Quaterniond& q, const RateWindow& window, std::size_t i,
                           double h) {
  const double t0 = window[i].t;
  Eigen::Vector3d a;
  Eigen::Vector3d b;
  window.interpolate(t0 + kGauss1 * h, t0 + kGauss2 * h, a, b);
  // Larger weight on the earlier Gauss point first; the other order is only second order.
  return q * expMap(h * (kAlpha * a + kBeta * b)) * expMap(h * (kBeta * a + kAlpha * b));
}

}  // namespace

Eigen::Vector3d RateWindow::interpolate(double t) const {
  Eigen::Vector3d w;
  Eigen::Vector3d unused;
  interpolate(t, t, w, unused);
  return w;
}

void RateWindow::interpolate(double t_a, double t_b, Eigen::Vector3d& w_a,
                             Eigen::Vector3d& w_b) const {
  // Lagrange form on times relative to the first node: stamps may be large (epoch seconds),
  // and differences of nearby doubles are exact where t - t_m computed directly is not.
  const double origin = (*this)[0].t;
  std::array<double, kCapacity> tau{};
  for (std::size_t j = 0; j < size_; ++j) tau[j] = (*this)[j].t - origin;
  const double tau_a = t_a - origin;
  const double tau_b = t_b - origin;
  w_a.setZero();
  w_b.setZero();
  for (std::size_t j = 0; j < size_; ++j) {
    double denominator = 1.0;
    double numerator_a = 1.0;
    double numerator_b = 1.0;
    for (std::size_t m = 0; m < size_; ++m) {
      if (m == j) continue;
      denominator *= tau[j] - tau[m];
      numerator_a *= tau_a - tau[m];
      numerator_b *= tau_b - tau[m];
    }
    const double inverse = 1.0 / denominator;
    const Eigen::Vector3d& w_j = (*this)[j].w_B;
    w_a += (numerator_a * inverse) * w_j;
    w_b += (numerator_b * inverse) * w_j;
  }
}

Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window, std::size_t i) {
  const RateSample& open = window[i];
  const RateSample& close = window[i + 1];
  const double h = close.t - open.t;
  switch (method) {
    case Integrator::Euler:
      return eulerStep(q_WB, open.w_B, h);
    case Integrator::Rk4:
      return rk4Step(q_WB, open.w_B, close.w_B, h);
    case Integrator::Exp:
      return q_WB * expMap(h * open.w_B);
    case Integrator::Exp2:
      return q_WB * expMap((0.5 * h) * (open.w_B + close.w_B));
    case Integrator::Cf4:
      return cf4Step(q_WB, window, i, h);
    default:
      throw std::invalid_argument("integrator '" + integratorName(method) +
                                  "' is not a kinematic method; accepted: euler rk4 exp exp2 cf4");
  }
}

Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window) {
  return kinematicStep(method, q_WB, window, window.size() - 2);
}

}  // namespace attitude_propagator
