#include "attitude_propagator/numerics/kinematic_step.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

namespace {

// Gauss–Legendre nodes and the weights of the fourth-order commutator-free step
// (docs/numerics.md §2): c = 1/2 -+ sqrt(3)/6, alpha = 1/4 + sqrt(3)/6, beta = 1/4 - sqrt(3)/6.
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

Eigen::Quaterniond eulerUpdate(const Eigen::Quaterniond& q, const Eigen::Vector3d& w0, double h) {
  return Eigen::Quaterniond(q.coeffs() + (0.5 * h) * timesPure(q.coeffs(), w0));
}

// Classical RK4 on dq/dt = 1/2 q (x) (0, w(t)), w linear between w0 and w1 (w_mid halfway).
Eigen::Quaterniond rk4Update(const Eigen::Quaterniond& q, const Eigen::Vector3d& w0,
                             const Eigen::Vector3d& w1, double h, const Eigen::Vector3d& w_mid) {
  const Eigen::Vector4d& y = q.coeffs();
  const Eigen::Vector4d k1 = 0.5 * timesPure(y, w0);
  const Eigen::Vector4d k2 = 0.5 * timesPure(y + (0.5 * h) * k1, w_mid);
  const Eigen::Vector4d k3 = 0.5 * timesPure(y + (0.5 * h) * k2, w_mid);
  const Eigen::Vector4d k4 = 0.5 * timesPure(y + h * k3, w1);
  return Eigen::Quaterniond(y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4));
}

// Weights c_j such that the rates at times x_a and x_b (relative to tau[0]) are sum_j c_j w_j
// over the n <= 4 samples with stamps tau[0..n-1].
//
// Instantaneous: the Lagrange basis, c_j = L_j(x) (the denominators shared by both times).
//
// IntervalAverage: the derivative of the Newton polynomial through the accumulated
// delta-angles theta_j, whose first divided differences are the means themselves,
// theta[t_{j-1}, t_j] = w_j:
//   w(x) = w_1 + theta[0,1,2] S1(x) + theta[0,1,2,3] S2(x),
//   theta[0,1,2] = (w_2 - w_1)/(tau_2 - tau_0),  theta[1,2,3] = (w_3 - w_2)/(tau_3 - tau_1),
//   theta[0,1,2,3] = (theta[1,2,3] - theta[0,1,2])/(tau_3 - tau_0),
//   S1 = (x - tau_0) + (x - tau_1),  S2 = sum of the pairwise products of (x - tau_0..2);
// so w = w_1 + a (w_2 - w_1) + b (w_3 - w_2) with a = (S1 - S2/(tau_3 - tau_0))/(tau_2 - tau_0)
// and b = S2/((tau_3 - tau_1)(tau_3 - tau_0)). c_0 = 0: the first sample's interval precedes
// tau_0.
void instantaneousWeights(const double* tau, std::size_t n, double x_a, double x_b, double* ca,
                          double* cb) {
  for (std::size_t j = 0; j < n; ++j) {
    double denominator = 1.0;
    double numerator_a = 1.0;
    double numerator_b = 1.0;
    for (std::size_t m = 0; m < n; ++m) {
      if (m == j) continue;
      denominator *= tau[j] - tau[m];
      numerator_a *= x_a - tau[m];
      numerator_b *= x_b - tau[m];
    }
    const double inverse = 1.0 / denominator;
    ca[j] = numerator_a * inverse;
    cb[j] = numerator_b * inverse;
  }
}

void averagedWeights(const double* tau, std::size_t n, double x, double r20, double r31, double r30,
                     double* c) {
  double a = 0.0;
  double b = 0.0;
  if (n >= 3) {
    const double u0 = x - tau[0], u1 = x - tau[1];
    const double s1 = u0 + u1;
    if (n == 4) {
      const double u2 = x - tau[2];
      const double s2 = u0 * u1 + (u0 + u1) * u2;
      a = (s1 - s2 * r30) * r20;
      b = s2 * r31 * r30;
    } else {
      a = s1 * r20;
    }
  }
  c[0] = 0.0;
  c[1] = 1.0 - a;
  if (n >= 3) c[2] = a - b;
  if (n == 4) c[3] = b;
}

void rateWeights(RateSamples kind, const double* tau, std::size_t n, double x_a, double x_b,
                 double* ca, double* cb) {
  if (kind == RateSamples::Instantaneous) {
    instantaneousWeights(tau, n, x_a, x_b, ca, cb);
    return;
  }
  const double r20 = n >= 3 ? 1.0 / (tau[2] - tau[0]) : 0.0;
  const double r31 = n == 4 ? 1.0 / (tau[3] - tau[1]) : 0.0;
  const double r30 = n == 4 ? 1.0 / (tau[3] - tau[0]) : 0.0;
  averagedWeights(tau, n, x_a, r20, r31, r30, ca);
  averagedWeights(tau, n, x_b, r20, r31, r30, cb);
}

// Noise gains of the Gauss-point weights ca, cb: of the step's mean rate (A + B)/2, which
// carries the rotation angle, and of A - B, which only enters the commutator term.
bool wellConditioned(const double* ca, const double* cb, std::size_t n) {
  double mean_gain = 0.0;
  double difference_gain = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    mean_gain += std::abs(ca[j] + cb[j]);
    difference_gain += std::abs(ca[j] - cb[j]);
  }
  return 0.5 * mean_gain <= kMaxNoiseGain && difference_gain <= kMaxDifferenceGain;
}

// The rates at the two Gauss points of interval i from the most samples around it whose
// weights are well conditioned (the linear interpolant, gains 1 and 2/√3 ≈ 1.15, always
// qualifies, and so does the interval's own mean for averaged samples).
void gaussRates(const RateWindow& window, std::size_t i, double h, RateSamples kind,
                Eigen::Vector3d& a, Eigen::Vector3d& b) {
  std::array<double, RateWindow::kCapacity> tau{}, ca{}, cb{};
  for (std::size_t n = window.size();; --n) {
    const std::size_t first = i + 2 > n ? i + 2 - n : 0;  // n samples holding the interval
    // Times relative to the first node: stamps may be large (epoch seconds), and differences
    // of nearby doubles are exact where t - t_m computed directly is not.
    const double origin = window[first].t;
    for (std::size_t j = 0; j < n; ++j) tau[j] = window[first + j].t - origin;
    const double x0 = window[i].t - origin;
    rateWeights(kind, tau.data(), n, x0 + kGauss1 * h, x0 + kGauss2 * h, ca.data(), cb.data());
    if (n == 2 || wellConditioned(ca.data(), cb.data(), n)) {
      a.setZero();
      b.setZero();
      for (std::size_t j = 0; j < n; ++j) {
        a += ca[j] * window[first + j].w_B;
        b += cb[j] * window[first + j].w_B;
      }
      return;
    }
  }
}

Eigen::Quaterniond cf4Update(const Eigen::Quaterniond& q, const RateWindow& window, std::size_t i,
                             double h, RateSamples kind) {
  Eigen::Vector3d a;
  Eigen::Vector3d b;
  gaussRates(window, i, h, kind, a, b);
  // Larger weight on the earlier Gauss point first; the other order is only second order.
  return q * expMap(h * (kAlpha * a + kBeta * b)) * expMap(h * (kBeta * a + kAlpha * b));
}

// Slope of the linear rate whose means over the intervals before and after window[i] are
// w_i and w_{i+1}: b = (w_{i+1} - w_i) / ((h_p + h)/2). Zero on the first interval of the
// window, where w_i belongs to an unknown interval.
Eigen::Vector3d averagedSlope(const RateWindow& window, std::size_t i, double h) {
  if (i == 0) return Eigen::Vector3d::Zero();
  const double h_p = window[i].t - window[i - 1].t;
  return (window[i + 1].w_B - window[i].w_B) * (2.0 / (h_p + h));
}

double intervalLength(const RateWindow& window, std::size_t i) {
  return window[i + 1].t - window[i].t;
}

}  // namespace

RateSamples rateSamplesFromName(const std::string& name) {
  if (name == "instantaneous") return RateSamples::Instantaneous;
  if (name == "interval_average") return RateSamples::IntervalAverage;
  throw std::invalid_argument("rate_samples: unknown value '" + logText(name) +
                              "'; accepted: instantaneous interval_average");
}

std::string rateSamplesName(RateSamples kind) {
  return kind == RateSamples::IntervalAverage ? "interval_average" : "instantaneous";
}

Eigen::Vector3d RateWindow::averagedRate(double t) const {
  std::array<double, kCapacity> tau{}, c{}, unused{};
  const double origin = (*this)[0].t;
  for (std::size_t j = 0; j < size_; ++j) tau[j] = (*this)[j].t - origin;
  rateWeights(RateSamples::IntervalAverage, tau.data(), size_, t - origin, t - origin, c.data(),
              unused.data());
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (std::size_t j = 1; j < size_; ++j) w += c[j] * (*this)[j].w_B;
  return w;
}

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
                                 const RateWindow& window, std::size_t i, RateSamples kind) {
  const KinematicStepFunction step = integratorInfo(method).kinematic_step;
  if (step == nullptr) {
    throw std::invalid_argument("integrator '" + integratorName(method) +
                                "' is not a kinematic method; accepted: " +
                                joinNames(integratorNames(integratorsFor(Model::Kinematic))));
  }
  return step(q_WB, window, i, kind);
}

Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window, RateSamples kind) {
  return kinematicStep(method, q_WB, window, window.size() - 2, kind);
}

// The methods' step functions (KinematicStepFunction, integrator.h), named only by the
// integrator table (integrator.cpp declares them above its rows). h = t_{i+1} - t_i.
// Instantaneous samples: w_j is the rate at t_j. Interval-averaged samples: w_{i+1} is the mean
// rate over the interval.

/// euler: q + (h/2) q (x) (0, w_i); averaged: q + (h/2) q (x) (0, w_{i+1}).
Eigen::Quaterniond kinematicEuler(const Eigen::Quaterniond& q_WB, const RateWindow& window,
                                  std::size_t i, RateSamples kind) {
  const std::size_t held = kind == RateSamples::IntervalAverage ? i + 1 : i;
  return eulerUpdate(q_WB, window[held].w_B, intervalLength(window, i));
}

/// rk4: classical RK4 with the rate at the midpoint from the linear interpolant; averaged: on
/// the linear rate whose means over the last two intervals are w_i, w_{i+1}.
Eigen::Quaterniond kinematicRk4(const Eigen::Quaterniond& q_WB, const RateWindow& window,
                                std::size_t i, RateSamples kind) {
  const double h = intervalLength(window, i);
  const Eigen::Vector3d& w0 = window[i].w_B;
  const Eigen::Vector3d& w1 = window[i + 1].w_B;
  if (kind == RateSamples::Instantaneous) return rk4Update(q_WB, w0, w1, h, 0.5 * (w0 + w1));
  const Eigen::Vector3d half_change = (0.5 * h) * averagedSlope(window, i, h);
  return rk4Update(q_WB, w1 - half_change, w1 + half_change, h, w1);
}

/// exp: q (x) Exp(h w_i), the rate of the sample opening the interval held; averaged:
/// q (x) Exp(h w_{i+1}), exact for a piecewise-constant rate.
Eigen::Quaterniond kinematicExp(const Eigen::Quaterniond& q_WB, const RateWindow& window,
                                std::size_t i, RateSamples kind) {
  const std::size_t held = kind == RateSamples::IntervalAverage ? i + 1 : i;
  return q_WB * expMap(intervalLength(window, i) * window[held].w_B);
}

/// exp2: q (x) Exp(h (w_i + w_{i+1})/2); averaged: q (x) Exp(h w_{i+1} + h^3/(6 (h + h_p))
/// w_i x w_{i+1}), the two-sample coning correction (Savage's (1/12) dtheta_{k-1} x dtheta_k
/// on a regular grid) on uneven stamps, h_p the previous interval; Exp(h w_{i+1}) on the first
/// interval.
Eigen::Quaterniond kinematicExp2(const Eigen::Quaterniond& q_WB, const RateWindow& window,
                                 std::size_t i, RateSamples kind) {
  const double h = intervalLength(window, i);
  const Eigen::Vector3d& w1 = window[i + 1].w_B;
  if (kind == RateSamples::Instantaneous) return q_WB * expMap((0.5 * h) * (window[i].w_B + w1));
  // Rotation vector of the linear rate w(s) = m + b (s - h/2) on [0, h] to third order:
  // int w + 1/2 int int_{r<s} w(r) x w(s) = h m + (h^3/12) m x b (Bortz).
  const Eigen::Vector3d slope = averagedSlope(window, i, h);
  return q_WB * expMap(h * w1 + (h * h * h / 12.0) * w1.cross(slope));
}

/// cf4: q (x) Exp(h(a A + b B)) (x) Exp(h(b A + a B)), A, B the window's interpolant at the
/// Gauss points. With four samples that is the cubic; with fewer, the
/// lower-degree interpolant (start-up). A window whose interpolant would amplify noise by more
/// than kMaxNoiseGain loses its oldest samples (lower degree). Averaged: A, B from
/// averagedRate() (the delta-angle polynomial), with the same noise guard.
Eigen::Quaterniond kinematicCf4(const Eigen::Quaterniond& q_WB, const RateWindow& window,
                                std::size_t i, RateSamples kind) {
  return cf4Update(q_WB, window, i, intervalLength(window, i), kind);
}

}  // namespace attitude_propagator
