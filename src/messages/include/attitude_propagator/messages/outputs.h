// The node's outputs as messages: the one encoding of AttitudeState, the republished
// sensor_msgs/Imu and the transform, shared by the node and propagate_bag, with the frames
// and axes `world_frame` chooses (docs/conventions.md §2.2).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/Imu.h>

#include <Eigen/Geometry>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"

namespace attitude_propagator {

class OutputEncoder {
 public:
  /// `model` and `integrator`: the names AttitudeState carries (resolved, never auto).
  OutputEncoder(const NodeConfig& config, std::string model, std::string integrator);
  /// The names from `engine` at each state: `integrator: auto` may change method per step
  /// (the kinematic model's rule), and AttitudeState says which one made the state.
  OutputEncoder(const NodeConfig& config, const AttitudeEngine& engine);

  /// The frame ids of AttitudeState: fixed_frame and body_frame, suffixed for the convention.
  const std::string& stateFixedFrame() const { return state_fixed_; }
  const std::string& stateBodyFrame() const { return state_body_; }

  /// The engine's state (REP-103 axes) in world_frame's axes: what AttitudeState and
  /// propagate_bag's CSV carry (the bias estimate and its standard deviations too).
  EngineState inWorldAxes(const EngineState& s) const;
  /// The state in world_frame's axes, stamped at its own stamp; gyro_bias is the bias in use
  /// (the engine's gyroBias(), or the gyro_bias parameter without an engine, plus the estimate).
  void state(const EngineState& s, AttitudeState& out) const;
  /// fixed_frame → body_frame (body_frame → fixed_frame with reverse_tf) in REP-103's axes:
  /// tf's tree is ROS's, whatever the messages' axes.
  void transform(const EngineState& s, geometry_msgs::TransformStamped& out) const;
  /// The input message with the orientation of its own frame (REP-145) in world_frame's fixed
  /// axes, its error covariance in that frame; `q_BS` is the mount it was rotated by.
  void imu(const sensor_msgs::Imu& input, const EngineState& s, const Eigen::Quaterniond& q_BS,
           sensor_msgs::Imu& out) const;
  /// The static transforms that name the convention's axes in tf: fixed_frame →
  /// fixed_frame_nwu or _ned, body_frame → body_frame_frd. None for enu.
  std::vector<geometry_msgs::TransformStamped> conventionFrames(const ros::Time& stamp) const;

 private:
  WorldConvention world_;
  std::string fixed_;
  std::string body_;
  bool reverse_tf_;
  std::string state_fixed_;
  std::string state_body_;
  std::string model_;
  std::string integrator_;
  Eigen::Vector3d gyro_bias_B_;  // the gyro_bias parameter, when there is no engine to ask
  const AttitudeEngine* engine_ = nullptr;
};

/// A topic by its role (the name a remap or launch argument changes) and its resolved name.
struct NamedTopic {
  std::string role;
  std::string name;
};

/// The feedback-loop rule: an output that resolves to the name of an input would be read back
/// as input (`imu_topic:=/imu/data` makes the output imu/data the input). The text naming the
/// first such output and input, both roles and the name; nothing when every name differs.
std::optional<std::string> feedbackLoop(const std::vector<NamedTopic>& outputs,
                                        const std::vector<NamedTopic>& inputs);

}  // namespace attitude_propagator
