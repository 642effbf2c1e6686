#include "attitude_propagator/numerics/world_convention.h"

#include <cmath>
#include <stdexcept>

#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

WorldConvention worldConventionFromName(const std::string& name) {
  if (name == "enu") return WorldConvention::Enu;
  if (name == "nwu") return WorldConvention::Nwu;
  if (name == "ned") return WorldConvention::Ned;
  throw std::invalid_argument("world_frame: unknown value '" + logText(name) +
                              "'; accepted: enu nwu ned");
}

std::string worldConventionName(WorldConvention convention) {
  switch (convention) {
    case WorldConvention::Nwu:
      return "nwu";
    case WorldConvention::Ned:
      return "ned";
    case WorldConvention::Enu:
      break;
  }
  return "enu";
}

std::string fixedFrameSuffix(WorldConvention convention) {
  return convention == WorldConvention::Enu ? "" : "_" + worldConventionName(convention);
}

std::string bodyFrameSuffix(WorldConvention convention) {
  return convention == WorldConvention::Ned ? "_frd" : "";
}

Eigen::Quaterniond fixedFromEnu(WorldConvention convention) {
  const double h = std::sqrt(0.5);
  switch (convention) {
    case WorldConvention::Nwu:
      // x_N = y_E, y_W = -x_E, z = z: a turn of -90° about z.
      return Eigen::Quaterniond(h, 0.0, 0.0, -h);
    case WorldConvention::Ned:
      // x_N = y_E, y_E = x_E, z_D = -z_U: a half turn about (x + y)/√2.
      return Eigen::Quaterniond(0.0, h, h, 0.0);
    case WorldConvention::Enu:
      break;
  }
  return Eigen::Quaterniond::Identity();
}

Eigen::Quaterniond fluFromBody(WorldConvention convention) {
  // FRD → FLU: y and z change sign, a half turn about x.
  if (convention == WorldConvention::Ned) return Eigen::Quaterniond(0.0, 1.0, 0.0, 0.0);
  return Eigen::Quaterniond::Identity();
}

Eigen::Quaterniond attitudeInConvention(WorldConvention convention,
                                        const Eigen::Quaterniond& q_EF) {
  return fixedFromEnu(convention) * q_EF * fluFromBody(convention);
}

Eigen::Quaterniond attitudeFromConvention(WorldConvention convention,
                                          const Eigen::Quaterniond& q_WB) {
  return fixedFromEnu(convention).conjugate() * q_WB * fluFromBody(convention).conjugate();
}

Eigen::Vector3d bodyVectorInConvention(WorldConvention convention, const Eigen::Vector3d& v_F) {
  return fluFromBody(convention).conjugate() * v_F;
}

Eigen::Vector3d bodyVectorFromConvention(WorldConvention convention, const Eigen::Vector3d& v_B) {
  return fluFromBody(convention) * v_B;
}

Eigen::Matrix3d bodyCovarianceInConvention(WorldConvention convention, const Eigen::Matrix3d& P_F) {
  const Eigen::Matrix3d C_BF = fluFromBody(convention).conjugate().toRotationMatrix();
  return C_BF * P_F * C_BF.transpose();
}

}  // namespace attitude_propagator
