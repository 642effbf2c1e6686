// The ROS wrapper shared by attitude_propagator_node and the nodelet (DESIGN §5, §6): turns
// input messages into core calls and the core's state into tf, imu/data, attitude_state and
// diagnostics. It owns the parameters, the time policy at the ROS level (receipt time, ROS
// time jumps, never publishing twice for one stamp), tf and diagnostics; the numerics are the
// core's (KinematicPropagator, DynamicPropagator, orientation_covariance.h).
//
// Threading: every callback (subscriptions, timers, services) runs on the callback queue of
// the node handles given to the constructor. The node spins one thread; the nodelet passes
// getNodeHandle()/getPrivateNodeHandle(), whose queue is single-threaded per nodelet, so the
// callbacks never run concurrently and the class needs no lock. The optional tf listener
// spins its own thread into its own buffer, which is thread-safe.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>

#include "attitude_propagator/SetState.h"
#include "attitude_propagator/dynamic_propagator.h"
#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/parameters.h"
#include "attitude_propagator/time_policy.h"

namespace attitude_propagator {

class AttitudePropagatorRos {
 public:
  /// Reads and validates the private parameters of pnh, builds the propagator and connects
  /// the topics, services and timers. Throws std::invalid_argument (message: the parameter,
  /// the problem and the accepted values) when a parameter is invalid; nothing is advertised
  /// then.
  AttitudePropagatorRos(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~AttitudePropagatorRos();

  AttitudePropagatorRos(const AttitudePropagatorRos&) = delete;
  AttitudePropagatorRos& operator=(const AttitudePropagatorRos&) = delete;

 private:
  /// What happened to input, shown in diagnostics.
  struct Counters {
    std::uint64_t received = 0;  // every message on an input topic
    std::uint64_t accepted = 0;
    std::uint64_t rejected_non_finite = 0;  // NaN / Inf values
    std::uint64_t rejected_no_rate = 0;     // REP-145: angular_velocity_covariance[0] == -1
    std::uint64_t rejected_type = 0;        // a message type the topic does not take
    std::uint64_t dropped_stale = 0;        // stamp at or before the last one
    std::uint64_t dropped_no_tf = 0;        // frame not (yet) known to tf
    std::uint64_t dropped_no_time = 0;      // unstamped, and sim time without /clock yet
    std::uint64_t late = 0;                 // dynamic: arrived after the timer passed its stamp
    std::uint64_t gaps = 0;                 // longer than max_dt: state held
    std::uint64_t resets = 0;               // backward jumps and ~reset calls
  };

  void advertise();
  void subscribe();
  void logModel() const;

  // Inputs.
  void onImu(const ros::MessageEvent<const sensor_msgs::Imu>& event);
  void onTwist(const ros::MessageEvent<const topic_tools::ShapeShifter>& event);
  void onTorque(const ros::MessageEvent<const topic_tools::ShapeShifter>& event);

  /// The vector a Twist/Wrench input carries, with the header of its stamped form if it had one.
  struct VectorInput {
    const geometry_msgs::Vector3* value = nullptr;
    ros::Time stamp;                        // zero when unstamped
    const std::string* frame_id = nullptr;  // null when unstamped
  };
  template <class Stamped, class Plain, class Inner, class Field>
  bool decodeVectorInput(const topic_tools::ShapeShifter& msg, const char* topic, const char* what,
                         Stamped& stamped, Plain& plain, Inner inner, Field field,
                         VectorInput& out);
  /// Dynamic model: a torque or a rate sample, applied when the timer reaches its stamp.
  struct DynamicInput {
    ros::Time stamp;
    bool is_torque = false;
    Eigen::Vector3d value = Eigen::Vector3d::Zero();  // tau (N m) or w_B (rad/s)
    TorqueFrame frame = TorqueFrame::Body;
    sensor_msgs::Imu::ConstPtr imu;  // a rate from an IMU: republished on imu/data
    Eigen::Quaterniond q_B_sensor = Eigen::Quaterniond::Identity();  // its mount
  };

  /// A body rate w_B at stamp with noise covariance R_B; imu (may be null) is republished on
  /// imu/data, q_B_sensor the rotation from the message's frame to the body.
  void handleRate(const ros::Time& stamp, const Eigen::Vector3d& w_B, const Eigen::Matrix3d& R_B,
                  const sensor_msgs::Imu::ConstPtr& imu, const Eigen::Quaterniond& q_B_sensor);
  void handleKinematicRate(const ros::Time& stamp, const Eigen::Vector3d& w_B,
                           const Eigen::Matrix3d& R_B, const sensor_msgs::Imu* imu,
                           const Eigen::Quaterniond& q_B_sensor);
  /// Dynamic model: an input stamped at or before the propagator's time is applied now (the
  /// core places a late one at its last grid point); a newer one waits in pending_ until the
  /// timer reaches its stamp.
  void submitDynamic(const DynamicInput& input);
  void applyDynamic(const DynamicInput& input);
  void applyPendingUpTo(const ros::Time& stamp);
  /// Rotation from the frame of a rate message to the body frame; nullptr while tf does not
  /// know it yet. Looked up once per frame id and cached (a sensor mount is static).
  const Eigen::Quaterniond* mountRotation(const std::string& frame_id);
  /// Rotation of a torque frame into the body frame, looked up per message (rare: a stamped
  /// torque in neither the body nor the fixed frame).
  std::optional<Eigen::Quaterniond> torqueFrameRotation(const std::string& frame_id);
  /// Sets input.value and input.frame from a torque tau given in frame_id (empty: the
  /// torque_frame parameter). False when the frame is not known to tf yet.
  bool resolveTorqueFrame(const std::string& frame_id, const Eigen::Vector3d& tau,
                          DynamicInput& input);
  void ensureTfListener();

  // Time.
  /// Seconds since origin_ (set at the first stamp): keeps the core's double time precise
  /// with epoch stamps.
  double coreTime(const ros::Time& stamp);
  /// Receipt time for unstamped (or zero-stamped) messages.
  static ros::Time stampOr(const ros::Time& stamp, const ros::Time& receipt);
  /// False (counted, warned) for a zero stamp: unstamped under sim time before any /clock.
  bool hasTime(const ros::Time& stamp, const char* input);
  /// Counts and warns for a core outcome; returns whether the state holds at the stamp.
  bool handleOutcome(StampOutcome outcome, const char* input, double stamp_s);
  /// Resets on ROS time (wall or /clock) going back by more than a second (looped bag).
  void checkRosTime();
  void onDynamicTimer(const ros::TimerEvent& event);
  /// Dynamic model: advances to the latest grid stamp at or before now and publishes there.
  void publishDynamic();
  void onWatchdog(const ros::WallTimerEvent& event);
  /// The latest multiple of 1/publish_rate at or before now.
  ros::Time gridStampAtOrBefore(const ros::Time& now) const;
  /// Back to the initial state; forget_time also forgets stamps (after a backward jump).
  void resetPropagator(bool forget_time);

  // Outputs.
  bool publishState(const ros::Time& stamp);
  void publishTf(const ros::Time& stamp, const Eigen::Quaterniond& q_WB);
  void publishImu(const sensor_msgs::Imu& input, const ros::Time& stamp,
                  const Eigen::Quaterniond& q_BI);
  Eigen::Quaterniond orientation() const;
  Eigen::Vector3d rate() const;

  // Services and diagnostics.
  bool onReset(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  bool onSetState(SetState::Request& request, SetState::Response& response);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  NodeConfig config_;
  std::optional<KinematicPropagator> kinematic_;
  std::optional<DynamicPropagator> dynamic_;
  std::vector<DynamicInput> pending_;  // sorted by stamp, capacity reserved

  Eigen::Matrix3d P_B_ = Eigen::Matrix3d::Zero();  // orientation covariance, body frame
  Eigen::Matrix3d default_R_;  // rate noise when a message carries none: stddev^2 I

  ros::Time origin_;          // zero: not yet set
  ros::Time last_published_;  // zero: nothing published since the last backward jump
  ros::Time last_ros_time_;

  // Sensor mount (frame of the rate messages -> body), cached.
  std::string mount_frame_;
  Eigen::Quaterniond q_B_mount_ = Eigen::Quaterniond::Identity();
  bool mount_known_ = false;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  // Scratch space for decoding ShapeShifter messages without allocating per message.
  std::vector<std::uint8_t> decode_buffer_;
  geometry_msgs::TwistStamped twist_stamped_;
  geometry_msgs::Twist twist_;
  geometry_msgs::WrenchStamped wrench_stamped_;
  geometry_msgs::Wrench wrench_;

  ros::Subscriber rate_sub_;
  ros::Subscriber torque_sub_;
  ros::Publisher tf_pub_;
  ros::Publisher imu_pub_;
  ros::Publisher state_pub_;
  ros::ServiceServer reset_srv_;
  ros::ServiceServer set_state_srv_;
  ros::Timer dynamic_timer_;
  ros::WallTimer watchdog_timer_;

  diagnostic_updater::Updater updater_;
  Counters counters_;
  std::uint64_t accepted_at_last_diagnosis_ = 0;
  ros::WallTime last_diagnosis_;
  ros::WallTime last_input_;
};

}  // namespace attitude_propagator
