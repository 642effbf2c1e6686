// What the tests sample: reproducible random numbers (the same on every standard library), the
// exact mean of a rate over a sample interval (what an interval-averaging gyro delivers), and
// directions spread evenly over the sphere.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

/// Reproducible uniform numbers in [0, 1): a 64-bit linear congruential generator (Knuth's
/// MMIX constants), the top 53 bits.
inline double uniformRandom(std::uint64_t& state) {
  state = state * 6364136223846793005ULL + 1442695040888963407ULL;
  return static_cast<double>(state >> 11) * 0x1.0p-53;
}

/// Reproducible standard normal numbers (Box-Muller on uniformRandom).
inline double normalRandom(std::uint64_t& state) {
  const double u1 = 1.0 - uniformRandom(state);  // in (0, 1]
  const double u2 = uniformRandom(state);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

/// Reproducible latencies of mean and standard deviation sigma: exponential draws (the wait in a
/// queue), never negative, their floor 0 and their density there 1 / sigma. A receipt stamp is
/// the sample's time plus a latency: no sample is received before it is taken.
inline double latencyRandom(std::uint64_t& state, double sigma) {
  return -sigma * std::log(1.0 - uniformRandom(state));
}

/// Mean of f over [a, b] by 5-point Gauss-Legendre: exact for polynomials of degree 9; for a
/// rate of frequency omega the error is about (omega (b - a))^10 / 10^9, below 1e-20 on the
/// tests' scenes (frequencies below 10 rad/s, b - a of a few ms).
template <class F>
Eigen::Vector3d intervalMean(F f, double a, double b) {
  static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                              0.4786286704993665, 0.2369268850561891};
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < 5; ++i) sum += w[i] * f(0.5 * (a + b) + 0.5 * (b - a) * x[i]);
  return 0.5 * sum;
}

/// The k-th of n unit directions spread evenly over the sphere (a Fibonacci lattice: heights
/// 1 - (2k + 1) / n, turned by the golden angle pi (3 - sqrt 5) from one to the next).
inline Eigen::Vector3d evenDirection(int k, int n) {
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  const double z = 1.0 - (2.0 * k + 1.0) / n;
  const double rho = std::sqrt(1.0 - z * z);
  return {rho * std::cos(golden * k), rho * std::sin(golden * k), z};
}
