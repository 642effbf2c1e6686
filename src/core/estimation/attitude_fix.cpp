#include "attitude_propagator/estimation/attitude_fix.h"

#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

Linearized AttitudeFix::linearize(const Eigen::Quaterniond& q_WB) const {
  Linearized m;
  m.r = logMap(q_WB.conjugate() * q_WB_);
  m.H = Eigen::Matrix3d::Identity();
  m.R = R_B_;
  return m;
}

void AttitudeFix::reset(Eigen::Quaterniond& q_WB, ErrorState& e) const {
  q_WB = q_WB_;
  e.P_B = clampOrientationCovariance(R_B_);
  e.P_Bb.setZero();
}

}  // namespace attitude_propagator
