// A simulated IMU on a motion given in closed form: the gyro (the body rate, a bias, white
// noise), the accelerometer (the specific force f_B = C_BW (a_W - g_W), noise) and the
// magnetometer (the earth's field plus a disturbance, noise), all in ENU and FLU as the core
// keeps them (docs/conventions.md). The scene of the gravity and field tests (test_aiding.cpp)
// and of the side-by-side benchmark (bench/), so both see the same streams.
#pragma once

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/gravity_direction.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace simulated_imu {

namespace ap = attitude_propagator;

constexpr double kDeg = M_PI / 180.0;

/// The earth's field in ENU (tesla): magnitude B, dip I (positive downward), declination D
/// (east of true north positive): B (cos I sin D, cos I cos D, -sin I).
inline Eigen::Vector3d earthField(double B, double dip, double declination) {
  return B * Eigen::Vector3d(std::cos(dip) * std::sin(declination),
                             std::cos(dip) * std::cos(declination), -std::sin(dip));
}

struct Motion {
  std::function<Eigen::Quaterniond(double)> attitude;  ///< q_WB(t)
  /// The body's linear acceleration in the world (m/s^2); none: at rest or uniform.
  std::function<Eigen::Vector3d(double)> acceleration_W;
};

struct Sensor {
  double rate = 100.0;                                  ///< samples per second
  double gyro_noise = 0.0;                              ///< rad/s per sample, per axis
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  ///< rad/s, body frame
  double accel_noise = 0.0;                             ///< m/s^2 per sample, per axis
  double mag_noise = 0.0;                               ///< tesla per sample, per axis
  Eigen::Vector3d field_W = earthField(50e-6, 60.0 * kDeg, 0.0);
  /// A field added in the world (a magnet near the sensor, a steel beam): tesla; none: zero.
  std::function<Eigen::Vector3d(double)> disturbance_W;
  unsigned seed = 1;
};

struct Sample {
  double t = 0.0;
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();  ///< the gyro's reading
  Eigen::Vector3d f_B = Eigen::Vector3d::Zero();  ///< the accelerometer's
  Eigen::Vector3d m_B = Eigen::Vector3d::Zero();  ///< the magnetometer's
  Eigen::Quaterniond truth = Eigen::Quaterniond::Identity();
  Eigen::Vector3d true_w_B = Eigen::Vector3d::Zero();
};

/// The body rate of q(t): w_B = 2 Im(q^-1 dq/dt), dq/dt by a central difference over 1e-5 s
/// (its error, 1e-11 of the rate's third derivative, is far below any sensor's).
inline Eigen::Vector3d bodyRate(const std::function<Eigen::Quaterniond(double)>& q, double t) {
  const double d = 1e-5;
  return ap::logMap(q(t - d).conjugate() * q(t + d)) / (2.0 * d);
}

inline std::vector<Sample> simulate(const Motion& motion, const Sensor& sensor, double seconds) {
  std::mt19937 rng(sensor.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto noise = [&](double sigma) -> Eigen::Vector3d {
    return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)) * sigma;
  };
  const Eigen::Vector3d g_W(0.0, 0.0, -ap::kStandardGravity);
  std::vector<Sample> samples;
  const int n = static_cast<int>(std::lround(seconds * sensor.rate));
  samples.reserve(static_cast<std::size_t>(n) + 1);
  for (int k = 0; k <= n; ++k) {
    Sample s;
    s.t = k / sensor.rate;
    s.truth = motion.attitude(s.t);
    s.true_w_B = bodyRate(motion.attitude, s.t);
    const Eigen::Quaterniond q_BW = s.truth.conjugate();
    const Eigen::Vector3d a_W =
        motion.acceleration_W ? motion.acceleration_W(s.t) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d field_W =
        sensor.field_W +
        (sensor.disturbance_W ? sensor.disturbance_W(s.t) : Eigen::Vector3d::Zero());
    s.w_B = s.true_w_B + sensor.gyro_bias + noise(sensor.gyro_noise);
    s.f_B = q_BW * (a_W - g_W) + noise(sensor.accel_noise);
    s.m_B = q_BW * field_W + noise(sensor.mag_noise);
    samples.push_back(s);
  }
  return samples;
}

/// The tilt error (rad): the angle between the world's up seen in the body by the estimate and
/// by the truth.
inline double tiltError(const Eigen::Quaterniond& estimate, const Eigen::Quaterniond& truth) {
  const Eigen::Vector3d a = estimate.conjugate() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d b = truth.conjugate() * Eigen::Vector3d::UnitZ();
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The heading error (rad): the angle about the world's up between the two body x axes
/// projected on the horizontal plane (the body's y axis when x is near vertical).
inline double headingError(const Eigen::Quaterniond& estimate, const Eigen::Quaterniond& truth) {
  const Eigen::Vector3d axis = std::abs((truth * Eigen::Vector3d::UnitX()).z()) < 0.9
                                   ? Eigen::Vector3d::UnitX()
                                   : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d a = estimate * axis;
  const Eigen::Vector3d b = truth * axis;
  return std::remainder(std::atan2(a.y(), a.x()) - std::atan2(b.y(), b.x()), 2.0 * M_PI);
}

}  // namespace simulated_imu
