// State and torque types of the dynamic model (docs/design.md §4), shared by the one-step
// integrators, the exact torque-free motion and the stateful DynamicPropagator.
#pragma once

#include <Eigen/Geometry>

namespace attitude_propagator {

/// Orientation and body rate of the user's body frame B.
struct DynamicState {
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();
};

/// Frame in which a torque sample is expressed. A fixed-frame torque t_W is held constant in
/// the world, so its body components follow the attitude: T_B = Q^T t_W (notes eq. 10).
enum class TorqueFrame { Body, Fixed };

/// A torque (N m) held constant over a step.
struct TorqueInput {
  Eigen::Vector3d tau = Eigen::Vector3d::Zero();
  TorqueFrame frame = TorqueFrame::Body;

  bool isZero() const { return tau.isZero(0.0); }
};

}  // namespace attitude_propagator
