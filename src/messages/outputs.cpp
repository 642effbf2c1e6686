#include "attitude_propagator/messages/outputs.h"

#include <utility>

#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/messages/conversions.h"

namespace attitude_propagator {

OutputEncoder::OutputEncoder(const NodeConfig& config, std::string model, std::string integrator)
    : world_(config.world),
      fixed_(config.parameters.fixed_frame),
      body_(config.parameters.body_frame),
      reverse_tf_(config.parameters.reverse_tf),
      state_fixed_(fixed_ + fixedFrameSuffix(world_)),
      state_body_(body_ + bodyFrameSuffix(world_)),
      model_(std::move(model)),
      integrator_(std::move(integrator)),
      gyro_bias_B_(engineConfig(config).gyro_bias_B) {}

EngineState OutputEncoder::inWorldAxes(const EngineState& s) const {
  if (world_ == WorldConvention::Enu) return s;
  EngineState out = s;
  out.q_WB = attitudeInConvention(world_, s.q_WB);
  out.P_B = bodyCovarianceInConvention(world_, s.P_B);
  out.w_B = bodyVectorInConvention(world_, s.w_B);
  out.M_B = bodyVectorInConvention(world_, s.M_B);
  out.gyro_bias_estimate_B = bodyVectorInConvention(world_, s.gyro_bias_estimate_B);
  // Standard deviations per axis: the convention's body axes are FLU's up to sign.
  out.gyro_bias_stddev_B = bodyVectorInConvention(world_, s.gyro_bias_stddev_B).cwiseAbs();
  return out;
}

OutputEncoder::OutputEncoder(const NodeConfig& config, const AttitudeEngine& engine)
    : OutputEncoder(config, engine.modelName(), integratorName(engine.integrator())) {
  engine_ = &engine;
}

void OutputEncoder::state(const EngineState& engine_state, AttitudeState& out) const {
  const EngineState s = inWorldAxes(engine_state);
  out.header.stamp = toRosTime(s.stamp);
  out.header.frame_id = state_fixed_;
  out.child_frame_id = state_body_;
  toMsg(s.q_WB, out.orientation);
  covarianceToMsg(s.P_B, out.orientation_covariance);
  toMsg(s.w_B, out.angular_velocity);
  toMsg(s.M_B, out.angular_momentum);
  out.kinetic_energy = s.kinetic_energy;
  out.norm_error = s.norm_error;
  out.model = model_;
  out.integrator = engine_ ? integratorName(engine_->integrator()) : integrator_;
  out.steps = s.steps;
  const Eigen::Vector3d& configured_B = engine_ ? engine_->gyroBias() : gyro_bias_B_;
  toMsg(bodyVectorInConvention(world_, configured_B) + s.gyro_bias_estimate_B, out.gyro_bias);
  toMsg(s.gyro_bias_stddev_B, out.gyro_bias_stddev);
}

void OutputEncoder::transform(const EngineState& s, geometry_msgs::TransformStamped& out) const {
  out.header.stamp = toRosTime(s.stamp);
  out.header.frame_id = reverse_tf_ ? body_ : fixed_;
  out.child_frame_id = reverse_tf_ ? fixed_ : body_;
  out.transform.translation = geometry_msgs::Vector3();
  toMsg(reverse_tf_ ? s.q_WB.conjugate() : s.q_WB, out.transform.rotation);
}

void OutputEncoder::imu(const sensor_msgs::Imu& input, const EngineState& s,
                        const Eigen::Quaterniond& q_BS, sensor_msgs::Imu& out) const {
  out = input;
  out.header.stamp = toRosTime(s.stamp);
  // The sensor's frame keeps its own axes: only the fixed axes follow world_frame.
  toMsg(fixedFromEnu(world_) * s.q_WB * q_BS, out.orientation);
  const Eigen::Matrix3d C_SB = q_BS.conjugate().toRotationMatrix();
  covarianceToMsg(rotateCovariance(s.P_B, C_SB), out.orientation_covariance);
}

std::vector<geometry_msgs::TransformStamped> OutputEncoder::conventionFrames(
    const ros::Time& stamp) const {
  std::vector<geometry_msgs::TransformStamped> frames;
  // A transform parent → child holds q_parent←child: q_EW for the fixed axes, q_FB for the body.
  auto add = [&](const std::string& parent, const std::string& child,
                 const Eigen::Quaterniond& q_PC) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = parent;
    t.child_frame_id = child;
    toMsg(q_PC, t.transform.rotation);
    frames.push_back(t);
  };
  if (state_fixed_ != fixed_) add(fixed_, state_fixed_, fixedFromEnu(world_).conjugate());
  if (state_body_ != body_) add(body_, state_body_, fluFromBody(world_));
  return frames;
}

std::optional<std::string> feedbackLoop(const std::vector<NamedTopic>& outputs,
                                        const std::vector<NamedTopic>& inputs) {
  for (const NamedTopic& out : outputs) {
    for (const NamedTopic& in : inputs) {
      if (out.name != in.name) continue;
      return "output " + out.role + " and input " + in.role + " are both " + out.name +
             ": the node would read what it publishes (a feedback loop); remap one of them";
    }
  }
  return std::nullopt;
}

}  // namespace attitude_propagator
