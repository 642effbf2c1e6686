#include "attitude_propagator/numerics/torque_free_motion.h"

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <boost/math/special_functions/ellint_rf.hpp>
#include <boost/math/special_functions/ellint_rj.hpp>

#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

TorqueFreeMotion::TorqueFreeMotion(const RigidBody& body, const DynamicState& x0, double t0)
    : t0_(t0), q_BP_(body.q_BP()), I_P_(body.principalMoments()) {
  if (!x0.q_WB.coeffs().allFinite() || !x0.w_B.allFinite() || !std::isfinite(t0)) {
    throw std::invalid_argument("TorqueFreeMotion: the initial state must be finite");
  }
  const std::optional<Eigen::Quaterniond> q0_WB = safeNormalized(x0.q_WB);
  if (!q0_WB) {
    throw std::invalid_argument("TorqueFreeMotion: the initial orientation is a zero quaternion");
  }
  q0_WP_ = *q0_WB * q_BP_;
  w0_P_ = q_BP_.conjugate() * x0.w_B;
  M0_P_ = I_P_.cwiseProduct(w0_P_);
  if (body.isSphere(kRelativeSymmetry)) {
    form_ = Form::Sphere;
  } else if (body.isSymmetric(kRelativeSymmetry)) {
    form_ = Form::SymmetricTop;
    initSymmetricTop(M0_P_, body.symmetryAxis(kRelativeSymmetry));
  } else {
    form_ = Form::Triaxial;
    // The triaxial constants square I w (G^2, Delta_j ~ I^2 |w|^2), which under- or
    // overflows for rates far from 1 rad/s (1e-159 rad/s on I = (1, 2, 3)). The motion from
    // s w0 is the motion from w0 run s times faster, w(t; s w0) = s w(s t; w0), so it is set
    // up at a rate of order one and evaluate() scales time and rate back; s is a power of two,
    // so the scaling itself is exact.
    int exponent = 0;
    std::frexp(w0_P_.cwiseAbs().maxCoeff(), &exponent);
    if (std::abs(exponent) > kUnscaledRateExponent) {
      rate_exponent_ = exponent;
      for (int i = 0; i < 3; ++i) w0_P_[i] = std::ldexp(w0_P_[i], -exponent);
      M0_P_ = I_P_.cwiseProduct(w0_P_);
    }
    initTriaxial(body, M0_P_);
  }
}

const char* TorqueFreeMotion::formName() const {
  switch (form_) {
    case Form::Sphere:
      return "sphere";
    case Form::SymmetricTop:
      return "symmetric_top";
    case Form::Triaxial:
      return "triaxial";
  }
  return "unknown";
}

double TorqueFreeMotion::bodyPeriod() const {
  if (regime_ == Regime::Separatrix) return std::numeric_limits<double>::infinity();
  if (regime_ == Regime::Steady) return 0.0;
  return 4.0 * K_ / std::abs(lambda());
}

void TorqueFreeMotion::initSymmetricTop(const Eigen::Vector3d& M_P, int axis) {
  axis_ = axis;
  const int j = (axis + 1) % 3;
  const int k = (axis + 2) % 3;
  const double I_perp = 0.5 * (I_P_[j] + I_P_[k]);
  precession_W_ = (q0_WP_ * M_P) / I_perp;
  spin_ = M_P[axis] * (1.0 / I_P_[axis] - 1.0 / I_perp);
}

namespace {

// Boost.Math promotes double to long double by default, about 8x slower (docs/numerics.md §6); the
// results without promotion differ by ~1e-14 relative.
using NoPromotion = boost::math::policies::policy<boost::math::policies::promote_double<false>>;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr double kPi = 3.14159265358979323846;

/// Rotation P(M) taking M/|M| onto the axis e_i (docs/numerics.md §6):
/// P = (c, (M/G x e_i) / (2c)), c = sqrt((1 + M_i/G)/2). Needs M_i > -G; here M_i >= 0.
Eigen::Quaterniond alignWithAxis(const Eigen::Vector3d& M, double G, int i) {
  const double c = std::sqrt(0.5 * (1.0 + M[i] / G));
  const Eigen::Vector3d v = M.cross(Eigen::Vector3d::Unit(i)) / (2.0 * c * G);
  return Eigen::Quaterniond(c, v.x(), v.y(), v.z());
}

/// Legendre's F(phi | k) = s R_F(c^2, c^2 + m_c s^2, 1) for |phi| <= pi/2 (s = sin phi,
/// c = cos phi; DLMF 19.25.5), with the complementary parameter m_c = 1 - k^2 given exactly:
/// 1 - k^2 s^2 = c^2 + m_c s^2 does not cancel near the separatrix (k -> 1).
double ellipticF(double s, double c, double m_c) {
  return s * boost::math::ellint_rf(c * c, c * c + m_c * s * s, 1.0, NoPromotion());
}

/// Legendre's Pi(phi, n | k) = integral of dθ / ((1 - n sin^2 θ) sqrt(1 - k^2 sin^2 θ)) for
/// |phi| <= pi/2, = F + (n/3) s^3 R_J(c^2, c^2 + m_c s^2, 1, 1 - n s^2) (DLMF 19.25.14, the
/// sign convention of Boost's ellint_3).
double ellipticPi(double s, double c, double n, double m_c) {
  const double c2 = c * c;
  const double d2 = c2 + m_c * s * s;
  return s * boost::math::ellint_rf(c2, d2, 1.0, NoPromotion()) +
         (n / 3.0) * s * s * s *
             boost::math::ellint_rj(c2, d2, 1.0, 1.0 - n * s * s, NoPromotion());
}

/// nu = F(phi0 | k) for phi0 = atan2(y, x), from sin phi0 = y/h and cos phi0 = x/h (h =
/// hypot(x, y)) without the angle itself: near the middle axis phi0 is close to +-pi/2, and
/// cos(phi0) would keep only the absolute round-off of the angle, which F multiplies by
/// 1/dn ~ 1/k'. With phi0 = j pi + phi_r, |phi_r| <= pi/2: F = 2 j K + F(phi_r), where
/// (sin phi_r, cos phi_r) = (-1)^j (sin phi0, cos phi0).
double startArgument(double y, double x, double K, double m_c) {
  const double h = std::hypot(x, y);
  double s = y / h;
  double c = x / h;
  double j = 0.0;
  if (c < 0.0) {
    j = std::copysign(1.0, s);
    s = -s;
    c = -c;
  }
  return 2.0 * j * K + ellipticF(s, c, m_c);
}

/// Rotation by pi about principal axis i.
Eigen::Quaterniond halfTurn(int i) {
  Eigen::Quaterniond q(0.0, 0.0, 0.0, 0.0);
  q.vec()[i] = 1.0;
  return q;
}

}  // namespace

void TorqueFreeMotion::initTriaxial(const RigidBody& body, const Eigen::Vector3d& M_P) {
  G_ = M_P.norm();
  // At rest or turning about a principal axis, w is constant: a steady rotation.
  const Eigen::Index zeros = (M_P.array() == 0.0).count();
  if (G_ == 0.0 || zeros >= 2) {
    regime_ = Regime::Steady;
    return;
  }

  // The sorted frame F (I1 < I2 < I3): a signed permutation of P, made a proper rotation by
  // flipping its third axis when the permutation is odd.
  const std::array<int, 3> sorted = body.sortedAxes();
  Eigen::Matrix3d C_PF = Eigen::Matrix3d::Zero();
  for (int j = 0; j < 3; ++j) C_PF(sorted[j], j) = 1.0;
  if (C_PF.determinant() < 0.0) C_PF.col(2) = -C_PF.col(2);
  Eigen::Quaterniond q_PF(C_PF);
  Eigen::Vector3d M = C_PF.transpose() * M_P;
  const Eigen::Vector3d I(I_P_[sorted[0]], I_P_[sorted[1]], I_P_[sorted[2]]);
  I_F_ = I;
  const double I1 = I[0], I2 = I[1], I3 = I[2];
  const double I21 = I2 - I1, I31 = I3 - I1, I32 = I3 - I2;

  // Cancellation-free Delta_j = G^2 - 2T I_j (docs/numerics.md §6): Delta1 >= 0 >= Delta3.
  const double M1s = M[0] * M[0], M3s = M[2] * M[2];

  // Cancellation-free Delta_j = G^2 - 2T I_j (docs/numerics.md §6), Delta1 >= 0 >= Delta3, written
  // with w (M_i^2 / I_i = I_i w_i^2) and summed in long double: near the separatrix Delta2 is
  // a difference of two nearly equal terms, and its relative error sets the error of the
  // period (dK = dm_c / (2 m_c)); the state as given is the truth to propagate.
  const Eigen::Vector3d w = C_PF.transpose() * w0_P_;  // a signed permutation: exact
  using Wide = long double;
  const Wide w1s = Wide(w[0]) * w[0], w2s = Wide(w[1]) * w[1], w3s = Wide(w[2]) * w[2];
  const Wide wI1 = I1, wI2 = I2, wI3 = I3;
  const Wide D1w = wI2 * (wI2 - wI1) * w2s + wI3 * (wI3 - wI1) * w3s;
  const Wide D3w = -(wI1 * (wI3 - wI1) * w1s + wI2 * (wI3 - wI2) * w2s);
  const Wide D2w = wI3 * (wI3 - wI2) * w3s - wI1 * (wI2 - wI1) * w1s;
  const double D1 = static_cast<double>(D1w);
  const double D2 = static_cast<double>(D2w);
  const double D3 = static_cast<double>(D3w);

  // Which side of the separatrix. On it (Delta2 = 0, or m_c below the normal doubles) the
  // hyperbolic solution applies; anywhere else the elliptic one, computed from m_c directly.
  const Wide m_c_i = D2w * (wI3 - wI1) / (D3w * (wI2 - wI1));   // case (i)
  const Wide m_c_ii = D2w * (wI3 - wI1) / (D1w * (wI3 - wI2));  // case (ii)
  const double m_c = static_cast<double>(D2w < 0 ? m_c_i : m_c_ii);
  if (D2w == 0 || !(m_c >= std::numeric_limits<double>::min())) {
    regime_ = Regime::Separatrix;
  } else {
    regime_ = D2 < 0.0 ? Regime::AboutSmallest : Regime::AboutLargest;
  }

  // Turn by pi about e2 (and, on the separatrix, about e3) so that the component M circulates
  // about is positive: the dn component, or both sech components on the separatrix.
  const int e = regime_ == Regime::AboutSmallest ? 0 : 2;
  axis_ = e;
  if (M[e] < 0.0) {
    q_PF = q_PF * halfTurn(1);
    M = Eigen::Vector3d(-M[0], M[1], -M[2]);
  }
  if (regime_ == Regime::Separatrix && M[0] < 0.0) {
    q_PF = q_PF * halfTurn(2);
    M = Eigen::Vector3d(-M[0], -M[1], M[2]);
  }
  q_PF_ = q_PF;

  const double B13 = std::sqrt(-I1 * D3 / I31);
  const double B31 = std::sqrt(I3 * D1 / I31);
  double psi0 = 0.0;  // the non-secular part of psi at t0
  if (regime_ == Regime::Separatrix) {
    // M = (B13 sech u, G tanh u, B31 sech u), u = lambda t + u0, lambda = sqrt(-D1 D3/(I1 I3))/G.
    // psi' = 2T/G - 2 d/dt atan(kappa tanh(u/2)), kappa = (G - B31)/B13 = B13/(G + B31)
    // (integrating psi' = G/I3 - D3/(I3 (G + M3)) with B13^2 + B31^2 = G^2 on the separatrix).
    B_[0] = B13;
    B_[1] = G_;
    B_[2] = B31;
    lambda_ = std::sqrt(-D1 * D3 / (I1 * I3)) / G_;
    k_ = 1.0;
    // u0 = atanh(M2/G), written so that M2 close to +-G does not cancel.
    const double off_axis = std::sqrt(M1s + M3s);
    nu_ = -std::copysign(std::log((G_ + std::abs(M[1])) / off_axis), M[1]);
    psi_rate_ = (M.cwiseProduct(M).cwiseQuotient(I).sum()) / G_;  // 2T/G
    atan_a_ = B13 / (G_ + B31);
    psi0 = -2.0 * std::atan(atan_a_ * std::tanh(-0.5 * nu_));
  } else {
    const bool about_smallest = regime_ == Regime::AboutSmallest;
    double phase_y, phase_x;  // the start phase phi0 = atan2(phase_y, phase_x)
    if (about_smallest) {
      // Case (i): M = (B13 dn, -B21 sn, B31 cn), e = e1.
      const double B21 = std::sqrt(I2 * D1 / I21);
      B_[0] = B13;
      B_[1] = B21;
      B_[2] = B31;
      lambda_ = -std::sqrt(D3 * (I1 - I2) / (I1 * I2 * I3));
      k_ = std::sqrt((-I32 * D1) / (D3 * I21));  // k^2 = 1 - m_c = I23 D1 / (D3 I21)
      phase_y = M[1] * B31;
      phase_x = M[2] * B21;
      psi_rate_ = G_ / I1;
      C_Pi_ = -G_ * I31 / (lambda_ * I1 * I3);
      n_ = I1 * I32 / (I3 * (I1 - I2));
      atan_a_ = std::sqrt(I2 * I31);
      atan_b_ = std::sqrt(I3 * I21);
      sigma_ = -1.0;
    } else {
      // Case (ii): M = (B13 cn, -B23 sn, B31 dn), e = e3.
      const double B23 = std::sqrt(I2 * D3 / (I2 - I3));
      B_[0] = B13;
      B_[1] = B23;
      B_[2] = B31;
      lambda_ = -std::sqrt(D1 * I32 / (I1 * I2 * I3));
      k_ = std::sqrt(((I1 - I2) * D3) / (D1 * I32));  // k^2 = 1 - m_c = I12 D3 / (D1 I32)
      phase_y = M[1] * B13;
      phase_x = M[0] * B23;
      psi_rate_ = G_ / I3;
      C_Pi_ = G_ * I31 / (lambda_ * I1 * I3);
      n_ = I3 * I21 / (I1 * (I2 - I3));
      atan_a_ = std::sqrt(I2 * I31);
      atan_b_ = std::sqrt(I1 * I32);
      sigma_ = 1.0;
    }
    // The complete and incomplete integrals come from Carlson's forms with m_c, exact to
    // round-off however close to the separatrix: from k alone, m_c = 1 - k^2 would keep only
    // its absolute round-off (1e-16), which near the separatrix shifts K, the period and the
    // flip times (measured: 1e-9 rad after 100 s at m_c = 5e-7).
    m_c_ = m_c;
    k_ = std::min(k_, 1.0);
    K_ = boost::math::ellint_rf(0.0, m_c, 1.0, NoPromotion());
    initJacobi();
    Pi_complete_ = K_ + (n_ / 3.0) * boost::math::ellint_rj(0.0, m_c, 1.0, 1.0 - n_, NoPromotion());
    nu_ = startArgument(phase_y, phase_x, K_, m_c);
    psi_half_period_ = 2.0 * C_Pi_ * Pi_complete_ + sigma_ * kPi;
    psi0 = ellipticPsi(-nu_);
  }
  psi_offset_ = psi0;
  R_ = (q0_WP_ * q_PF_) * alignWithAxis(M, G_, axis_).conjugate();
}

double TorqueFreeMotion::ellipticPsi(double u) const {
  // u = 2K j + r with |r| <= K: am(u) = j pi + am(r), sn(u) = (-1)^j sn(r) etc., and
  // Pi(j pi + phi) = 2 j Pi(n | k) + Pi(phi), so the cost does not grow with |u|.
  double sn, cn, dn;
  const double j = std::nearbyint(u / (2.0 * K_));
  reduced(u, j, sn, cn, dn);
  return psiFromReduced(j, sn, cn);
}

void TorqueFreeMotion::initJacobi() {
  // Arithmetic-geometric mean from a0 = 1, b0 = k' = sqrt(m_c) (A&S 17.6, DLMF 19.8(i)):
  // a_{n+1} = (a_n + b_n)/2, b_{n+1} = sqrt(a_n b_n), c_{n+1} = (a_n - b_n)/2. The moduli of
  // the descending Landen transformation are k_{n+1} = c_{n+1}/a_{n+1} = (1 - k'_n)/(1 + k'_n),
  // k'_n = b_n/a_n, and 1 - k_{n+1} = b_n/a_{n+1} keeps the digits of a tiny k' (near the
  // separatrix k' may be 1e-20, and 1 - k_1 from k_1 would be lost). Starting from sqrt(m_c)
  // rather than from k keeps m_c's digits.
  double a = 1.0;
  double b = std::sqrt(m_c_);
  agm_steps_ = 0;
  while (agm_steps_ < kMaxAgmSteps) {
    const double a_next = 0.5 * (a + b);
    const double c_next = 0.5 * (a - b);
    landen_k_[agm_steps_] = c_next / a_next;
    landen_one_minus_k_[agm_steps_] = b / a_next;
    b = std::sqrt(a * b);
    a = a_next;
    ++agm_steps_;
    if (std::abs(c_next) <= kEpsilon * a) break;
  }
  landen_scale_ = a;  // a_N: the argument at the last modulus (~0) is a_N r, and K = pi/(2 a_N)
}

void TorqueFreeMotion::reduced(double u, double j, double& sn, double& cn, double& dn) const {
  const double r = u - 2.0 * K_ * j;
  // Descending Landen (Gauss) transformation in algebraic form (DLMF 22.7.1-3): with
  // k1 = (1 - k')/(1 + k') and v = r/(1 + k1), writing s, c, d for sn, cn, dn(v, k1),
  //   sn(r, k) = (1 + k1) s / (1 + k1 s^2),  cn(r, k) = c d / (1 + k1 s^2),
  //   dn(r, k) = ((1 - k1) + k1 c^2) / (1 + k1 s^2),
  // from sin, cos and 1 at the last modulus (below the round-off), where the argument is
  // a_N r (|a_N r| <= pi/2). Every step multiplies, divides or adds terms of one sign, so cn
  // and dn keep their relative precision where they are small (r near +-K, close to the
  // middle axis). The angular form, am = phi_0 from phi_{n-1} = (phi_n + asin((c_n/a_n)
  // sin phi_n))/2, gives cn = cos(am) with an absolute error only, and its asin near 1 there
  // loses half the digits (measured: 1.2e-10 off the middle axis, on an orbit whose m_c is at
  // its round-off, cn came out wrong by 14 times its size); the psi term multiplies the error
  // of am by 1/dn.
  double s = std::sin(landen_scale_ * r);
  double c = std::cos(landen_scale_ * r);
  double d = 1.0;
  for (int i = agm_steps_ - 1; i >= 0; --i) {
    const double k1 = landen_k_[i];
    const double inverse = 1.0 / (1.0 + k1 * s * s);
    const double sn_up = (1.0 + k1) * s * inverse;
    const double cn_up = c * d * inverse;
    d = (landen_one_minus_k_[i] + k1 * c * c) * inverse;  // 1 - k1 s^2 with s^2 = 1 - c^2
    s = sn_up;
    c = cn_up;
  }
  sn = s;
  cn = c;
  dn = d;
}

double TorqueFreeMotion::psiFromReduced(double j, double sn_r, double cn_r) const {
  // am(r) in [-pi/2, pi/2] since cn(r) >= 0 for |r| <= K.
  const double am_r = std::atan2(sn_r, cn_r);
  const double Pi_r = ellipticPi(sn_r, cn_r, n_, m_c_);
  // atan2(a sin(am), b cos(am)) made continuous: am + atan2((a - b) s c, b c^2 + a s^2),
  // whose second term has a positive denominator and the period pi of s c.
  const double a = atan_a_, b = atan_b_;
  const double wrap = std::atan2((a - b) * sn_r * cn_r, b * cn_r * cn_r + a * sn_r * sn_r);
  return j * psi_half_period_ + C_Pi_ * Pi_r + sigma_ * (am_r + wrap);
}

void TorqueFreeMotion::triaxialAt(double tau, Eigen::Vector3d& M_F,
                                  Eigen::Quaterniond& q_WF) const {
  double psi;
  if (regime_ == Regime::Separatrix) {
    // sech u, tanh u and tanh(u/2) from one exponential, stable for any |u|.
    const double u = lambda_ * tau - nu_;
    const double x = std::exp(-std::abs(u));
    const double sign = u < 0.0 ? -1.0 : 1.0;
    const double sech = 2.0 * x / (1.0 + x * x);
    const double tanh = sign * (1.0 - x * x) / (1.0 + x * x);
    const double tanh_half = sign * (1.0 - x) / (1.0 + x);
    M_F = Eigen::Vector3d(B_[0] * sech, G_ * tanh, B_[2] * sech);
    psi = psi_rate_ * tau - 2.0 * std::atan(atan_a_ * tanh_half) - psi_offset_;
  } else {
    const double u = lambda_ * tau - nu_;
    const double j = std::nearbyint(u / (2.0 * K_));
    double sn, cn, dn;
    reduced(u, j, sn, cn, dn);
    psi = psi_rate_ * tau + psiFromReduced(j, sn, cn) - psi_offset_;
    const double parity = std::fmod(j, 2.0) == 0.0 ? 1.0 : -1.0;
    sn *= parity;
    cn *= parity;
    if (regime_ == Regime::AboutSmallest) {
      M_F = Eigen::Vector3d(B_[0] * dn, -B_[1] * sn, B_[2] * cn);
    } else {
      M_F = Eigen::Vector3d(B_[0] * cn, -B_[1] * sn, B_[2] * dn);
    }
  }
  const double half = 0.5 * psi;
  Eigen::Quaterniond spin(std::cos(half), 0.0, 0.0, 0.0);
  spin.vec()[axis_] = std::sin(half);
  q_WF = R_ * spin * alignWithAxis(M_F, G_, axis_);
}

DynamicState TorqueFreeMotion::evaluate(double t) const {
  const double tau = t - t0_;
  Eigen::Quaterniond q_WP = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero();
  switch (form_) {
    case Form::Sphere:
      q_WP = q0_WP_ * expMap(tau * w0_P_);
      w_P = w0_P_;
      break;
    case Form::SymmetricTop: {
      const Eigen::Vector3d spin = tau * spin_ * Eigen::Vector3d::Unit(axis_);
      q_WP = expMap(tau * precession_W_) * q0_WP_ * expMap(spin);
      const Eigen::Vector3d M_P = expMap(-spin) * M0_P_;
      w_P = M_P.cwiseQuotient(I_P_);
      break;
    }
    case Form::Triaxial: {
      // Time and rate of the motion set up at the scaled rate (see the constructor).
      const double scaled_tau = rate_exponent_ == 0 ? tau : std::ldexp(tau, rate_exponent_);
      if (regime_ == Regime::Steady) {
        q_WP = q0_WP_ * expMap(scaled_tau * w0_P_);
        w_P = w0_P_;
      } else {
        Eigen::Vector3d M_F;
        Eigen::Quaterniond q_WF;
        triaxialAt(scaled_tau, M_F, q_WF);
        q_WP = q_WF * q_PF_.conjugate();
        w_P = q_PF_ * Eigen::Vector3d(M_F.cwiseQuotient(I_F_));
      }
      if (rate_exponent_ != 0) {
        for (int i = 0; i < 3; ++i) w_P[i] = std::ldexp(w_P[i], rate_exponent_);
      }
      break;
    }
  }
  DynamicState x;
  x.q_WB = q_WP * q_BP_.conjugate();
  x.w_B = q_BP_ * w_P;
  return x;
}

}  // namespace attitude_propagator
