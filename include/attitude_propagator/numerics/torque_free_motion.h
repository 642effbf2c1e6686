// The exact motion of a free rigid body (integrator `exact`, docs/design.md §4, docs/numerics.md
// §6): the body rate w(t) and the attitude q(t) in closed form, in the cheapest form the body
// allows.
//
// - sphere (I1 = I2 = I3): w constant, q(t) = q0 (x) Exp(t w).
// - symmetric top (two equal moments I_perp, symmetry axis e_s with moment I_s):
//   q(t) = Exp(t m_W / I_perp) (x) q0 (x) Exp(t c e_s), c = M_s (1/I_s - 1/I_perp), and
//   M(t) = Exp(-t c e_s) M0 in the body.
// - triaxial: Jacobi elliptic functions (docs/numerics.md §6 table, cases i and ii on either side
// of
//   the separatrix, iii on it). With the moments sorted I1 < I2 < I3 and e the axis M
//   circulates about (e1 in case i, e3 in case ii, e3 on the separatrix),
//   q(t) = R (x) Exp(psi(t) e) (x) P(M(t)), where P(M) is the rotation taking M/|M| onto e
//   and psi(t) follows from psi' = G/I_e - (Delta_e / (G I_e)) / (1 + M_e/G) in closed form
//   with Legendre's incomplete integral of the third kind. R is fixed by q(t0).
//
// Each evaluation costs the same however far t is from t0: the argument u of the elliptic
// functions is reduced modulo 2K and the whole half-periods are added to am(u) and to
// Pi(am u, n | k) from cached complete integrals.
//
// Precision near the separatrix (k -> 1) hangs on the complementary parameter m_c = 1 - k^2,
// which is computed from the state without cancellation and used directly: K, F and Pi in
// Carlson's form (Boost.Math's ellint_rf and ellint_rj, without promotion to long double,
// 8x faster, docs/numerics.md §6), and sn, cn, dn by the descending Landen transformation in
// its algebraic (Gauss) form with the moduli of the AGM started from sqrt(m_c). Boost's
// jacobi_elliptic, ellint_1 and ellint_3 take k, whose 1 - k^2 keeps only the absolute
// round-off 1e-16 of m_c: measured 5e-10 rad after 100 s at m_c = 5e-7, 1e-6 rad at
// m_c = 5e-11.
//
// Precision near the middle axis (cn or dn tiny) hangs on never forming the Jacobi amplitude
// as an angle: the algebraic Landen steps keep cn and dn relative, where cos(am) would keep an
// absolute error that the psi term divides by dn (measured 4.4e-5 rad over 20 s at 1e-12 rad/s
// off the middle axis before, 4e-14 now).
#pragma once

#include <cmath>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/rigid_body.h"

namespace attitude_propagator {

class TorqueFreeMotion {
 public:
  /// Which closed form applies (by the body's moments, to kRelativeSymmetry).
  enum class Form { Sphere, SymmetricTop, Triaxial };
  /// For a triaxial body, where M0 lies (docs/numerics.md §6, with I1 < I2 < I3): circulating about
  /// the axis of the smallest moment (case i, Delta2 < 0), of the largest (case ii), on the
  /// separatrix (case iii, Delta2 = 0 to round-off), or at rest / a steady rotation about a
  /// principal axis (M along an axis; w constant).
  enum class Regime { Steady, AboutSmallest, AboutLargest, Separatrix };

  /// Moments equal to this relative tolerance count as equal: the body is treated as a
  /// symmetric top or a sphere. The attitude error of that approximation grows like
  /// kRelativeSymmetry |w| t (1e-8 rad after 10^4 rad of rotation).
  static constexpr double kRelativeSymmetry = 1e-12;

  /// The motion through state x0 at time t0. Throws std::invalid_argument for a non-finite
  /// state or a zero quaternion (it is normalised otherwise).
  TorqueFreeMotion(const RigidBody& body, const DynamicState& x0, double t0 = 0.0);

  /// State at time t (any t, before or after t0), in the user's body frame.
  DynamicState evaluate(double t) const;

  Form form() const { return form_; }
  Regime regime() const { return regime_; }
  /// "sphere", "symmetric_top" or "triaxial".
  const char* formName() const;

  /// Triaxial cases i and ii: the modulus k, the rate lambda of u = lambda t - nu, and the
  /// body period 4 K(k) / |lambda| of M (infinite on the separatrix, 0 when not elliptic).
  double modulus() const { return k_; }
  double lambda() const { return std::ldexp(lambda_, rate_exponent_); }
  double bodyPeriod() const;

 private:
  void initSymmetricTop(const Eigen::Vector3d& M_P, int axis);
  void initTriaxial(const RigidBody& body, const Eigen::Vector3d& M_P);
  /// M(t) and q_WF(t) in the elliptic frame F for the triaxial case, tau = t - t0.
  void triaxialAt(double tau, Eigen::Vector3d& M_F, Eigen::Quaterniond& q_WF) const;
  /// The non-secular part of psi at u (cases i and ii).
  double ellipticPsi(double u) const;
  /// Caches the moduli of the descending Landen transformation (the arithmetic-geometric mean
  /// of 1 and sqrt(m_c)) for reduced().
  void initJacobi();
  /// sn, cn, dn of r = u - 2 K j.
  void reduced(double u, double j, double& sn, double& cn, double& dn) const;
  /// The non-secular part of psi from j and sn(r), cn(r): j (2 C_Pi Pi(n|k) + sigma pi) +
  /// C_Pi Pi(am r, n | k) + sigma atan2(a sn, b cn) (continuous in u).
  double psiFromReduced(double j, double sn_r, double cn_r) const;

  Form form_;
  Regime regime_ = Regime::Steady;
  double t0_;
  Eigen::Quaterniond q_BP_;
  Eigen::Vector3d I_P_;
  Eigen::Quaterniond q0_WP_;
  Eigen::Vector3d w0_P_;
  Eigen::Vector3d M0_P_;

  // Symmetric top: precession m_W / I_perp and body spin c about axis_.
  Eigen::Vector3d precession_W_ = Eigen::Vector3d::Zero();
  double spin_ = 0.0;
  int axis_ = 2;

  // Triaxial: the frame F (moments sorted I1 < I2 < I3, turned by pi where needed so that the
  // component of M it circulates about is positive) and the cached constants.
  Eigen::Quaterniond q_PF_ = Eigen::Quaterniond::Identity();
  Eigen::Quaterniond R_ = Eigen::Quaterniond::Identity();  // q_WF(t) = R Exp(psi e) P(M)
  Eigen::Vector3d I_F_ = Eigen::Vector3d::Ones();
  double G_ = 0.0;
  double k_ = 0.0;
  double m_c_ = 1.0;  // complementary parameter 1 - k^2, computed without cancellation
  double lambda_ = 0.0;
  double nu_ = 0.0;
  double K_ = 0.0;                 // complete integral of the first kind K(k)
  double Pi_complete_ = 0.0;       // complete integral of the third kind Pi(n | k)
  double n_ = 0.0;                 // characteristic of Pi
  double B_[3] = {0.0, 0.0, 0.0};  // amplitudes of M1, M2, M3 (B13, B21 or B23, B31)
  double psi_rate_ = 0.0;          // the secular rate G / I_e
  double C_Pi_ = 0.0;              // coefficient of Pi(am u, n | k) in psi
  double atan_a_ = 0.0;            // psi's atan2(a sn, b cn) term
  double atan_b_ = 0.0;
  double sigma_ = 0.0;
  double psi_half_period_ = 0.0;           // growth of psi's non-secular part per 2K of u
  static constexpr int kMaxAgmSteps = 16;  // the AGM converges quadratically: ~6 for m_c = 1e-30
  int agm_steps_ = 0;
  double landen_k_[kMaxAgmSteps] = {};            // the moduli k_1, k_2, ... of the Landen steps
  double landen_one_minus_k_[kMaxAgmSteps] = {};  // 1 - k_n, without cancellation
  double landen_scale_ = 0.0;                     // a_N, with K = pi / (2 a_N)
  double psi_offset_ = 0.0;  // the psi terms at t0, subtracted so that psi(t0) = 0
  // Triaxial: the constants above describe the motion from w0 / 2^rate_exponent_ (rates
  // whose binary exponent exceeds kUnscaledRateExponent are brought to order one).
  static constexpr int kUnscaledRateExponent = 32;
  int rate_exponent_ = 0;
};

}  // namespace attitude_propagator
