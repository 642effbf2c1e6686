// The axes a user reads and gives attitudes in (`world_frame`), and the one rule that maps them
// to the axes the propagators work in (docs/conventions.md §2.2).
//
// The propagators work in ROS's axes (REP-103): a fixed frame x east, y north, z up (ENU), and
// a body x forward, y left, z up (FLU), the axes every ROS driver's body and sensor frames have
// and tf's mounts join. `world_frame` chooses the fixed axes of every attitude the node takes
// (initial_orientation, ~set_state) and gives (AttitudeState, the republished IMU), with the
// body axes that go with them, as imu_filter_madgwick and mavros name them:
//
//   enu: fixed x east, y north, z up;    body FLU (x forward, y left, z up)
//   nwu: fixed x north, y west, z up;    body FLU
//   ned: fixed x north, y east, z down;  body FRD (x forward, y right, z down)
//
// An attitude q_WB in those axes is q_WB = q_WE · q_EF · q_FB, with q_EF the propagators' ENU
// ← FLU attitude, q_WE the chosen fixed axes from ENU, q_FB the chosen body axes into FLU.
#pragma once

#include <string>

#include <Eigen/Geometry>

namespace attitude_propagator {

enum class WorldConvention { Enu, Nwu, Ned };

/// Parses a `world_frame` value; throws std::invalid_argument naming the accepted values.
WorldConvention worldConventionFromName(const std::string& name);
std::string worldConventionName(WorldConvention convention);
/// The suffix of the frames the node names for the convention's axes ("", "_nwu", "_ned";
/// "", "", "_frd" for the body).
std::string fixedFrameSuffix(WorldConvention convention);
std::string bodyFrameSuffix(WorldConvention convention);

/// q_WE: takes ENU coordinates to the convention's fixed coordinates.
Eigen::Quaterniond fixedFromEnu(WorldConvention convention);
/// q_FB: takes the convention's body coordinates to FLU coordinates.
Eigen::Quaterniond fluFromBody(WorldConvention convention);

/// The propagators' attitude q_EF (ENU ← FLU) as the convention's q_WB.
Eigen::Quaterniond attitudeInConvention(WorldConvention convention, const Eigen::Quaterniond& q_EF);
/// The convention's q_WB as the propagators' q_EF: the inverse of attitudeInConvention.
Eigen::Quaterniond attitudeFromConvention(WorldConvention convention,
                                          const Eigen::Quaterniond& q_WB);
/// A body vector (rate, momentum) from FLU to the convention's body axes.
Eigen::Vector3d bodyVectorInConvention(WorldConvention convention, const Eigen::Vector3d& v_F);
/// A body vector from the convention's body axes to FLU.
Eigen::Vector3d bodyVectorFromConvention(WorldConvention convention, const Eigen::Vector3d& v_B);
/// A body-frame covariance (the orientation error's) from FLU to the convention's body axes:
/// C P Cᵀ with C the body axes ← FLU.
Eigen::Matrix3d bodyCovarianceInConvention(WorldConvention convention, const Eigen::Matrix3d& P_F);

}  // namespace attitude_propagator
