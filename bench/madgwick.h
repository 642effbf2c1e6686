// A Madgwick gradient-descent AHRS (S. Madgwick, "An efficient orientation filter for inertial
// and inertial/magnetic sensor arrays", 2010), written from the paper's equations as
// imu_filter_madgwick implements them, for the side-by-side benchmark (bench_ahrs). The world is
// ENU (imu_filter_madgwick's default) and q is the sensor's orientation relative to the earth,
// our q_WB, so that a body vector v_B is R(q) v_B in the world.
//
//   gyro:        q_dot = 1/2 q (x) (0, w)                                       (paper eq. 11)
//   objective:   f(q, d, s) = q* (x) d (x) q - s = R(q)^T d - s                  (eq. 20)
//   step:        q_dot -= beta grad / |grad|,  grad = J^T f                      (eqs. 33, 42-44)
//   gravity:     d = (0, 0, 1) (ENU up: the accelerometer reads +g when level), s = f / |f|
//   field (MARG): h = q (x) m (x) q*, b = (0, sqrt(h_x^2 + h_y^2), h_z): north is ENU's y
//                 (the paper's b = (b_x, 0, b_z) is NWU's x), s = m / |m|           (eqs. 45-46)
//
// Like imu_filter_madgwick with its defaults: no gyro bias drift term (zeta = 0), the state
// started from the first sample (the tilt from the force, the heading from the field).
#pragma once

#include <cmath>

#include <Eigen/Geometry>

namespace bench {

class Madgwick {
 public:
  explicit Madgwick(double beta) : beta_(beta) {}

  /// The orientation from one sample: up from the force; with a field, east = m x up (the
  /// field's north and down parts: north x up = east), north = up x east; else any heading.
  void initialise(const Eigen::Vector3d& f_B, const Eigen::Vector3d* m_B) {
    const Eigen::Vector3d up = f_B.normalized();
    if (m_B == nullptr) {
      q_ = Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ());
      return;
    }
    const Eigen::Vector3d east = m_B->cross(up).normalized();
    const Eigen::Vector3d north = up.cross(east);
    Eigen::Matrix3d C_BW;  // columns: the world's axes in the body
    C_BW << east, north, up;
    q_ = Eigen::Quaterniond(Eigen::Matrix3d(C_BW.transpose()));
    q_.normalize();
  }

  /// One sample: the gyro's w (rad/s) over dt, the force f and, when given, the field m.
  void update(const Eigen::Vector3d& w, const Eigen::Vector3d& f_B, const Eigen::Vector3d* m_B,
              double dt) {
    Eigen::Vector4d q(q_.w(), q_.x(), q_.y(), q_.z());
    // 1/2 q (x) (0, w), components (w, x, y, z).
    Eigen::Vector4d q_dot = 0.5 * Eigen::Vector4d(-q(1) * w.x() - q(2) * w.y() - q(3) * w.z(),
                                                  q(0) * w.x() + q(2) * w.z() - q(3) * w.y(),
                                                  q(0) * w.y() - q(1) * w.z() + q(3) * w.x(),
                                                  q(0) * w.z() + q(1) * w.y() - q(2) * w.x());
    if (f_B.squaredNorm() > 0.0) {
      Eigen::Vector4d grad = gradient(q, Eigen::Vector3d::UnitZ(), f_B.normalized());
      if (m_B != nullptr && m_B->squaredNorm() > 0.0) {
        const Eigen::Vector3d h = q_ * m_B->normalized();  // the field in the world
        grad +=
            gradient(q, Eigen::Vector3d(0.0, std::hypot(h.x(), h.y()), h.z()), m_B->normalized());
      }
      const double n = grad.norm();
      if (n > 0.0) q_dot -= beta_ * grad / n;
    }
    q += q_dot * dt;
    q.normalize();
    q_ = Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  }

  const Eigen::Quaterniond& q_WB() const { return q_; }

  /// J^T f for the reference d and the measurement s (unit vectors), paper eqs. 20-21 with
  /// q = (q1, q2, q3, q4) = (w, x, y, z).
  static Eigen::Vector4d gradient(const Eigen::Vector4d& q, const Eigen::Vector3d& d,
                                  const Eigen::Vector3d& s) {
    const double q1 = q(0), q2 = q(1), q3 = q(2), q4 = q(3);
    const double dx = d.x(), dy = d.y(), dz = d.z();
    const Eigen::Vector3d f(2 * dx * (0.5 - q3 * q3 - q4 * q4) + 2 * dy * (q1 * q4 + q2 * q3) +
                                2 * dz * (q2 * q4 - q1 * q3) - s.x(),
                            2 * dx * (q2 * q3 - q1 * q4) + 2 * dy * (0.5 - q2 * q2 - q4 * q4) +
                                2 * dz * (q1 * q2 + q3 * q4) - s.y(),
                            2 * dx * (q1 * q3 + q2 * q4) + 2 * dy * (q3 * q4 - q1 * q2) +
                                2 * dz * (0.5 - q2 * q2 - q3 * q3) - s.z());
    Eigen::Matrix<double, 3, 4> J;
    J << 2 * dy * q4 - 2 * dz * q3, 2 * dy * q3 + 2 * dz * q4,
        -4 * dx * q3 + 2 * dy * q2 - 2 * dz * q1, -4 * dx * q4 + 2 * dy * q1 + 2 * dz * q2,
        -2 * dx * q4 + 2 * dz * q2, 2 * dx * q3 - 4 * dy * q2 + 2 * dz * q1,
        2 * dx * q2 + 2 * dz * q4, -2 * dx * q1 - 4 * dy * q4 + 2 * dz * q3,
        2 * dx * q3 - 2 * dy * q2, 2 * dx * q4 - 2 * dy * q1 - 4 * dz * q2,
        2 * dx * q1 + 2 * dy * q4 - 4 * dz * q3, 2 * dx * q2 + 2 * dy * q3;
    return J.transpose() * f;
  }

 private:
  double beta_;
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
};

}  // namespace bench
