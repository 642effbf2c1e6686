#include "attitude_propagator/estimation/magnetic_heading.h"

#include <algorithm>
#include <cmath>

#include "attitude_propagator/estimation/gravity_direction.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

namespace {

double wrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }

}  // namespace

MagneticHeading::MagneticHeading(const Eigen::Vector3d& m_B, const Eigen::Matrix3d& covariance_B,
                                 double declination, double gate, double tilt_variance)
    : m_B_(m_B),
      covariance_B_(covariance_B),
      reference_heading_(M_PI / 2.0 - declination),
      gate_(gate),
      tilt_variance_(tilt_variance) {}

Linearized MagneticHeading::linearize(const Eigen::Quaterniond& q_WB) const {
  const Eigen::Vector3d m_W = q_WB * m_B_;
  const Eigen::Vector2d h = m_W.head<2>();
  // The heading's noise: the field's across h, over |h|^2 (floored: a field seen nearly
  // vertical says nothing of the heading).
  const double h2 = std::max(h.squaredNorm(), 1e-6 * m_W.squaredNorm() + 1e-30);
  const Eigen::Vector3d across = Eigen::Vector3d(-h.y(), h.x(), 0.0) / std::sqrt(h2);
  const Eigen::Matrix3d C = q_WB.toRotationMatrix();
  Linearized m;
  m.r = MeasurementResidual::Constant(1, wrapAngle(reference_heading_ - std::atan2(h.y(), h.x())));
  // A body error dtheta turns the measured field in the world by C (dtheta x m_B), and h's
  // direction by its part across h over |h|: H = -n^T C [m_B]x / |h|. About the body's up this
  // is 1 (the heading itself); across it, tan(dip) times a tilt about h's direction, which the
  // innovation's covariance then holds, while the correction stays on the vertical.
  const Eigen::Matrix3d m_cross = (Eigen::Matrix3d() << 0.0, -m_B_.z(), m_B_.y(), m_B_.z(), 0.0,
                                   -m_B_.x(), -m_B_.y(), m_B_.x(), 0.0)
                                      .finished();
  m.H = -(across.transpose() * C * m_cross) / std::sqrt(h2);
  m.R =
      MeasurementNoise::Constant(1, 1, across.dot(C * covariance_B_ * C.transpose() * across) / h2);
  // A tilt off by more than P says (linear acceleration) turns into heading alike.
  const Eigen::Vector3d u = bodyUp(q_WB);
  m.R(0, 0) +=
      tilt_variance_ * (m.H * (Eigen::Matrix3d::Identity() - u * u.transpose())).squaredNorm();
  return m;
}

Eigen::Matrix3d MagneticHeading::correctionAxes(const Eigen::Quaterniond& q_WB) const {
  const Eigen::Vector3d u = bodyUp(q_WB);
  return u * u.transpose();
}

void MagneticHeading::reset(Eigen::Quaterniond& q_WB, ErrorState& e) const {
  const Linearized m = linearize(q_WB);
  const Eigen::Vector3d u = bodyUp(q_WB);
  q_WB = (q_WB * expMap(m.r(0) * u)).normalized();  // R_z(r) C_WB = C_WB Exp(r u)
  const Eigen::Matrix3d tilt = Eigen::Matrix3d::Identity() - u * u.transpose();
  e.P_B = clampOrientationCovariance(tilt * e.P_B * tilt + m.R(0, 0) * u * u.transpose());
  e.P_Bb = tilt * e.P_Bb;
}

double dipAngle(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB) {
  const Eigen::Vector3d m_W = q_WB * m_B;
  return std::asin(std::clamp(-m_W.z() / m_W.norm(), -1.0, 1.0));
}

bool MagneticReference::matches(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB) const {
  if (!magnitude_) return true;
  return std::abs(m_B.norm() / *magnitude_ - 1.0) <= kMagMagnitudeTolerance &&
         std::abs(dipAngle(m_B, q_WB) - dip_) <= kMagDipTolerance;
}

void MagneticReference::follow(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB) {
  if (!magnitude_) {
    restart(m_B, q_WB);
    return;
  }
  *magnitude_ += kMagReferenceFollow * (m_B.norm() - *magnitude_);
  dip_ += kMagReferenceFollow * (dipAngle(m_B, q_WB) - dip_);
}

void MagneticReference::restart(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB) {
  magnitude_ = m_B.norm();
  dip_ = dipAngle(m_B, q_WB);
}

}  // namespace attitude_propagator
