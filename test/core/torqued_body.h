// The torqued scene of the dynamic tests: an asymmetric body whose user frame B is not its
// principal frame, spinning about no principal axis, under a body torque or a fixed-frame torque
// along no principal axis. So the gyroscopic term (I w) x w, the torque and the conversions
// between B and the principal frame all act at once, and a fixed-frame torque turns in the body
// as the body turns.
#pragma once

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/rigid_body.h"

namespace torqued_body {

namespace ap = attitude_propagator;

/// Principal moments 1.07, 2.10 and 2.83 kg m^2, principal axes off the body axes.
inline Eigen::Matrix3d tensor_B() {
  Eigen::Matrix3d I_B;
  I_B << 1.2, 0.3, -0.2,  //
      0.3, 2.0, 0.1,      //
      -0.2, 0.1, 2.8;
  return I_B;
}

inline ap::RigidBody body() { return ap::RigidBody::fromTensor(tensor_B()); }

/// About 1.4 rad/s about no principal axis, from an arbitrary attitude.
inline ap::DynamicState initial() {
  ap::DynamicState x;
  x.q_WB = Eigen::Quaterniond(0.8, -0.3, 0.4, 0.2).normalized();
  x.w_B = Eigen::Vector3d(0.7, -0.4, 1.1);
  return x;
}

/// A torque of about 0.6 N m in the given frame.
inline ap::TorqueInput torque(ap::TorqueFrame frame) {
  ap::TorqueInput t;
  t.frame = frame;
  t.tau = frame == ap::TorqueFrame::Body ? Eigen::Vector3d(0.3, -0.5, 0.2)
                                         : Eigen::Vector3d(-0.4, 0.2, 0.5);
  return t;
}

inline const char* frameName(ap::TorqueFrame frame) {
  return frame == ap::TorqueFrame::Body ? "body" : "fixed";
}

}  // namespace torqued_body
