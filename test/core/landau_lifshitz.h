// The free body's motion of the angular momentum in the body, as the textbook writes it
// (Landau & Lifshitz, Mechanics §37), from the principal moments and the body rate alone: the
// modulus and frequency of the Jacobi functions and the period, with K(k) from the
// arithmetic-geometric mean. Written for the tests, independently of the core's closed form
// (which works from the cancellation-free Delta_j, Carlson's integrals and sorted frames).
#pragma once

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

#include <Eigen/Core>
#include <boost/math/constants/constants.hpp>

namespace landau_lifshitz {

using Real = long double;

/// Arithmetic-geometric mean of a > 0 and b > 0 (quadratic convergence: 6 steps for b = 1e-6).
inline Real agm(Real a, Real b) {
  for (int i = 0; i < 64 && std::abs(a - b) > 4 * LDBL_EPSILON * a; ++i) {
    const Real mean = 0.5L * (a + b);
    b = std::sqrt(a * b);
    a = mean;
  }
  return a;
}

/// Complete elliptic integral of the first kind, K(k) = pi / (2 AGM(1, k')), from the
/// complementary parameter m_c = k'^2 = 1 - k^2 (Abramowitz & Stegun 17.6).
inline Real completeEllipticK(Real m_c) {
  return boost::math::constants::pi<Real>() / (2 * agm(1, std::sqrt(m_c)));
}

/// Modulus, frequency and period of w(t) = (cn, sn, dn)-type motion of a triaxial free body.
struct EllipticMotion {
  Real k2;         ///< k^2
  Real m_c;        ///< 1 - k^2
  Real frequency;  ///< omega in tau = omega t, the argument of the Jacobi functions
  Real period;     ///< 4 K(k) / omega: sn and cn have period 4K in tau
};

/// With the moments sorted I1 < I2 < I3 (the labels follow the sorted order), the energy
/// E = 1/2 sum I_i w_i^2 and M^2 = sum I_i^2 w_i^2, §37 gives for M^2 > 2 E I2
///   omega^2 = (I3 - I2)(M^2 - 2 E I1) / (I1 I2 I3),
///   k^2 = (I2 - I1)(2 E I3 - M^2) / ((I3 - I2)(M^2 - 2 E I1)),
/// and for M^2 < 2 E I2 the same with I1 and I3 exchanged. Long double throughout: near the
/// middle axis M^2 - 2 E I2 cancels to a relative 1e-6 or so, which long double keeps to
/// 1e-13 relative. Needs three distinct moments and M^2 != 2 E I2 (not on the separatrix).
inline EllipticMotion ellipticMotion(const Eigen::Vector3d& moments, const Eigen::Vector3d& w) {
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(),
            [&moments](int a, int b) { return moments[a] < moments[b]; });
  Real I[3], two_E = 0, M2 = 0;
  for (int j = 0; j < 3; ++j) {
    I[j] = moments[order[j]];
    const Real wj = w[order[j]];
    two_E += I[j] * wj * wj;
    M2 += I[j] * I[j] * wj * wj;
  }
  Real I1 = I[0], I3 = I[2];
  const Real I2 = I[1];
  if (M2 < two_E * I2) std::swap(I1, I3);
  EllipticMotion motion;
  motion.frequency = std::sqrt((I3 - I2) * (M2 - two_E * I1) / (I1 * I2 * I3));
  motion.k2 = (I2 - I1) * (two_E * I3 - M2) / ((I3 - I2) * (M2 - two_E * I1));
  motion.m_c = 1 - motion.k2;
  motion.period = 4 * completeEllipticK(motion.m_c) / motion.frequency;
  return motion;
}

}  // namespace landau_lifshitz
