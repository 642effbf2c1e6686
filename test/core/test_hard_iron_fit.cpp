// The magnetometer's own field from its reads (hard_iron_fit.h, numerics.md §7.2): the sphere
// against reads placed on a known one, the centre's standard deviation against its closed form
// for reads spread evenly over the sphere, 3 sigma^2 / n per axis, and the reads that fix no
// sphere (too few, one circle, a body turned about one axis) said to be so.
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/hard_iron_fit.h"
#include "sampling.h"

namespace {

namespace ap = attitude_propagator;

// n directions spread evenly over the sphere (sampling.h).
std::vector<Eigen::Vector3d> evenDirections(int n) {
  std::vector<Eigen::Vector3d> u;
  for (int i = 0; i < n; ++i) u.push_back(evenDirection(i, n));
  return u;
}

// A centre on no axis, the size of a board's own field, and the earth's field at mid latitude.
const Eigen::Vector3d kCentre(12e-6, -31e-6, 7e-6);
constexpr double kRadius = 48e-6;

ap::HardIronFit fitOf(const std::vector<Eigen::Vector3d>& reads) {
  ap::HardIronFit fit;
  for (const Eigen::Vector3d& m : reads) fit.add(m);
  return fit;
}

std::vector<Eigen::Vector3d> onTheSphere(const std::vector<Eigen::Vector3d>& directions) {
  std::vector<Eigen::Vector3d> reads;
  for (const Eigen::Vector3d& u : directions) reads.push_back(kCentre + kRadius * u);
  return reads;
}

TEST(HardIronFit, ReadsOnASphereGiveItsCentreAndRadius) {
  const std::optional<ap::HardIronSphere> sphere = fitOf(onTheSphere(evenDirections(200))).solve();
  ASSERT_TRUE(sphere);
  EXPECT_LE((sphere->centre - kCentre).norm(), 1e-9 * kRadius);
  EXPECT_NEAR(sphere->radius, kRadius, 1e-9 * kRadius);
  // The scatter is formed from sums of |m|^4: rounding leaves about 1e-8 of the radius.
  EXPECT_LE(sphere->off_rms, 1e-7 * kRadius);
  EXPECT_EQ(sphere->reads, 200u);
  // Evenly spread: the reads' covariance is r^2 / 3 on every axis.
  EXPECT_NEAR(sphere->least_spread, kRadius / std::sqrt(3.0), 0.02 * kRadius);
  EXPECT_TRUE(sphere->determined());
}

// Noise sigma per axis: a read is off the sphere by its radial part, sigma; the centre's
// variance per axis is sigma^2 (sum u u^T)^-1 = 3 sigma^2 / n, the estimate within its stddev.
TEST(HardIronFit, TheCentresStddevIsTheScatterOverTheReadsSeen) {
  const double sigma = 0.5e-6;
  const int n = 4000;
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<Eigen::Vector3d> reads = onTheSphere(evenDirections(n));
  for (Eigen::Vector3d& m : reads)
    m += Eigen::Vector3d(noise(random), noise(random), noise(random));
  const auto sphere = fitOf(reads).solve();
  ASSERT_TRUE(sphere);
  const double expected = sigma * std::sqrt(3.0 / n);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sphere->centre_stddev(i), expected, 0.1 * expected) << i;
    EXPECT_LE(std::abs(sphere->centre(i) - kCentre(i)), 4.0 * expected) << i;
  }
  EXPECT_NEAR(sphere->off_rms, sigma, 0.1 * sigma);
  EXPECT_TRUE(sphere->determined());
}

// The stddev's side of determined(): reads off the sphere by 2 uT (radially, alternating in
// sign) spread every way; few of them leave each axis' stddev above 1 uT (about 2 uT sqrt(3 / n)
// sqrt(n / (n - 4)): 1.6 uT at 8 reads), more bring it under (0.58 uT at 40), the spread being
// wide enough throughout.
TEST(HardIronFit, DeterminedOnceEveryAxisIsKnownWithinAMicrotesla) {
  for (const int n : {8, 40}) {
    std::vector<Eigen::Vector3d> reads;
    const std::vector<Eigen::Vector3d> u = evenDirections(n);
    for (int i = 0; i < n; ++i)
      reads.push_back(kCentre + (kRadius + (i % 2 ? 2e-6 : -2e-6)) * u[i]);
    const auto sphere = fitOf(reads).solve();
    ASSERT_TRUE(sphere) << n;
    EXPECT_GE(sphere->least_spread, ap::kHardIronSpread * sphere->off_rms) << n;
    const bool known = sphere->centre_stddev.maxCoeff() <= ap::kHardIronDetermined;
    EXPECT_EQ(known, n == 40) << n << ": " << sphere->centre_stddev.transpose();
    EXPECT_EQ(sphere->determined(), n == 40) << n;
  }
}

// Four unknowns and a scatter: four reads are none, five (on no circle) a sphere.
TEST(HardIronFit, FiveReadsAtLeast) {
  const std::vector<Eigen::Vector3d> reads = onTheSphere(evenDirections(5));
  ap::HardIronFit fit;
  for (int i = 0; i < 4; ++i) fit.add(reads[i]);
  EXPECT_FALSE(fit.solve());
  fit.add(reads[4]);
  const auto sphere = fit.solve();
  ASSERT_TRUE(sphere);
  EXPECT_LE((sphere->centre - kCentre).norm(), 1e-9 * kRadius);
  fit.add(Eigen::Vector3d(NAN, 0.0, 0.0));  // no read: not taken
  fit.add(Eigen::Vector3d::Zero());
  fit.add(Eigen::Vector3d(0.0, 0.0, 1e6));  // a driver's error: it would outweigh the rest
  fit.add(Eigen::Vector3d(0.0, 0.0, -ap::kMaxFieldRead * 1.001));
  EXPECT_EQ(fit.count(), 5u);
  EXPECT_EQ(fit.solve()->centre, sphere->centre);
}

// A body turned about one axis alone (a vehicle on level ground, the board mounted askew, so the
// axis is on none of the board's): the earth's field goes round a circle about that axis, which
// many spheres pass through. Exact: no sphere; with the sensor's noise the centre across the
// axis is known, along it not, and the fit says it is not determined.
TEST(HardIronFit, ABodyTurnedAboutOneAxisFixesNoSphere) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.81).normalized();
  const Eigen::Vector3d e1 = axis.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d e2 = axis.cross(e1);
  const double horizontal = 20e-6, vertical = -44e-6;  // a dip of 65 degrees
  std::vector<Eigen::Vector3d> circle;
  for (int i = 0; i < 3000; ++i) {
    const double yaw = 2.0 * M_PI * i / 3000;
    circle.emplace_back(kCentre + horizontal * (std::cos(yaw) * e1 + std::sin(yaw) * e2) +
                        vertical * axis);
  }
  EXPECT_FALSE(fitOf(circle).solve());
  std::mt19937 random(5);
  std::normal_distribution<double> noise(0.0, 0.3e-6);
  for (Eigen::Vector3d& m : circle)
    m += Eigen::Vector3d(noise(random), noise(random), noise(random));
  const auto sphere = fitOf(circle).solve();
  ASSERT_TRUE(sphere);  // the noise alone spreads the reads off the circle
  const Eigen::Vector3d off = sphere->centre - kCentre;
  EXPECT_LE(std::abs(off.dot(e1)), 1e-7);
  EXPECT_LE(std::abs(off.dot(e2)), 1e-7);
  // Along the axis the reads spread by their noise alone, on no axis of the board.
  EXPECT_LT(sphere->least_spread, 2.0 * 0.3e-6);
  EXPECT_LT(sphere->least_spread, ap::kHardIronSpread * sphere->off_rms);
  EXPECT_FALSE(sphere->determined());
}

}  // namespace
