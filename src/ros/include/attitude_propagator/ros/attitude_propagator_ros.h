// The ROS wrapper shared by attitude_propagator_node and the nodelet: hands input messages to
// the message layer's decoders (input_decoders.h) and their inputs to the core engine, tells the
// engine what time it is, and publishes what the engine hands back as tf, imu/data,
// attitude_state and diagnostics. Every policy (time, queueing, publish grid, covariance,
// counting) is the engine's (attitude_propagator/engine.h), every reading of a message the
// message layer's; this class owns the ROS side only: parameters, topics, the tf listener the
// decoders look sensor frames up in, timers, services and logging. What it logs and shows in
// diagnostics is composed without ROS beside it: note_text.h, input_text.h, model_text.h,
// tf_conflict_watch.h, node_diagnostics.h (with input_window.h), live_parameters.h.
//
// Threading: every callback (subscriptions, timers, services) runs on the callback queue of
// the node handles given to the constructor. The node spins one thread; the nodelet passes
// getNodeHandle()/getPrivateNodeHandle(), whose queue is single-threaded per nodelet, so the
// callbacks never run concurrently and the class needs no lock. The optional tf listener
// spins its own thread into its own buffer, which is thread-safe.
//
// No exception leaves a callback: each runs inside guarded(), which logs and counts.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <std_srvs/Empty.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>

#include "attitude_propagator/AttitudePropagatorConfig.h"
#include "attitude_propagator/SetState.h"
#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/messages/outputs.h"
#include "attitude_propagator/ros/fix_input.h"
#include "attitude_propagator/ros/hand_over_bound.h"
#include "attitude_propagator/ros/instance_log.h"
#include "attitude_propagator/ros/log_text.h"
#include "attitude_propagator/ros/node_diagnostics.h"
#include "attitude_propagator/ros/tf_conflict_watch.h"

namespace attitude_propagator {

class AttitudePropagatorRos : public EngineSink {
 public:
  /// Reads and validates the private parameters of pnh, builds the engine and connects the
  /// topics, services and timers. Throws std::invalid_argument (message: the parameter, the
  /// problem and the accepted values) when a parameter is invalid; nothing is advertised then.
  AttitudePropagatorRos(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~AttitudePropagatorRos() override;

  AttitudePropagatorRos(const AttitudePropagatorRos&) = delete;
  AttitudePropagatorRos& operator=(const AttitudePropagatorRos&) = delete;

  // EngineSink: what the engine produces.
  void publishState(const EngineState& state) override;
  void inputApplied(const Input& input, const EngineState& state) override;
  void note(const EngineNote& note) override;

 private:
  /// Throws (the node refuses to start) when an output resolves to an input's name
  /// (outputs.h, feedbackLoop).
  void refuseFeedbackLoops() const;
  void advertise();
  void subscribe();
  /// Subscribes the /tf and /tf_static watch when publish_tf is on and tf_conflict is not
  /// `ignore`, unsubscribes it otherwise; a fresh subscription receives the latched
  /// /tf_static parents again.
  void watchTf();
  void logModel();
  /// ~resolved_model and ~resolved_integrator: what `auto` (or the user) chose, on the
  /// parameter server next to the parameters as given.
  void writeResolved() const;

  /// Runs f, turning any exception into a throttled error and a count, so none crosses a
  /// callback (a numeric surprise must never take the node down).
  template <class F>
  void guarded(const char* where, F&& f);
  /// Logs a line composed elsewhere (note_text.h, input_text.h ...) in this instance's name,
  /// throttled per kind (kWarnPeriod of wall time) unless its kind is empty (instance_log.h).
  /// Every line of the wrapper goes through here.
  void log(const std::optional<LogLine>& line);

  // Inputs.
  void onImu(const ros::MessageEvent<const sensor_msgs::Imu>& event);
  void onTwist(const ros::MessageEvent<const topic_tools::ShapeShifter>& event);
  void onTorque(const ros::MessageEvent<const topic_tools::ShapeShifter>& event);
  void onClock(const ros::MessageEvent<const rosgraph_msgs::Clock>& event);
  /// use_mag: a magnetometer sample on imu/mag, a measurement of the heading.
  void onMag(const ros::MessageEvent<const sensor_msgs::MagneticField>& event);
  /// A gyro bias, in force for rates stamped at or after its stamp.
  void onGyroBias(const geometry_msgs::Vector3Stamped::ConstPtr& msg);
  /// An absolute attitude fix (fix_input.h).
  void onFix(const ros::MessageEvent<const topic_tools::ShapeShifter>& event);
  /// Logs the decoders' warnings of frame ids with a leading '/', once per frame.
  void warnFrames();

  /// Counts and logs a refused input (false), or logs a newly looked-up mount (true).
  bool taken(const DecodedInput& in, const char* topic);
  /// Counts a refusal once and logs it, throttled per kind.
  void refused(const Refusal& refusal, const char* topic);
  void ensureTfListener();
  /// Stops listening to tf once no input needs a lookup any more (`mount_settled`: the rates'
  /// mount is kept, or they need none), or the listener would digest our own /tf.
  void releaseTfListener(bool mount_settled);
  /// Hands an input to the engine and notes when input last arrived (diagnostics).
  void submit(const Input& input);

  // Time.
  void onDynamicTimer(const ros::TimerEvent& event);
  void onWatchdog(const ros::WallTimerEvent& event);
  /// Under wall time the clock is read from callbacks; under sim time /clock drives.
  void pollClock();

  /// A message on /tf or /tf_static from another node, for the tf-conflict watch
  /// (tf_conflict_watch.h).
  void onTfSeen(const ros::MessageEvent<const tf2_msgs::TFMessage>& event, bool latched);

  // Outputs.
  void publishTf(const EngineState& state);
  /// The encoder for the configuration and integrator in force.
  void rebuildEncoder();
  /// world_frame's named axes on /tf_static (none for enu).
  void publishConventionFrames();
  void publishImu(const sensor_msgs::Imu& input, const EngineState& state,
                  const Eigen::Quaterniond& q_BS);
  /// Outputs dropped at the hand-over bound, all three outputs (hand_over_bound.h).
  std::uint64_t outputsDropped() const;
  /// Whether an output may be handed over; logs the drop (throttled) when not.
  bool handOver(HandOverBound& bound);

  // Services and diagnostics.
  bool onReset(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  bool onSetState(SetState::Request& request, SetState::Response& response);
  /// The status computed by node_diagnostics.h.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// dynamic_reconfigure (live_parameters.h): validated like the start-up parameters; a
  /// refused change is logged and the values shown in rqt_reconfigure go back to those in force.
  void onReconfigure(AttitudePropagatorConfig& live, std::uint32_t level);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  ros::NodeHandle imu_nh_;  // "imu" under nh_: `imu:=other` moves imu/data_raw and imu/data
  InstanceLog log_;
  // A nodelet: the manager's other nodelets publish under the same node name as we do.
  bool in_manager_;
  NodeConfig config_;
  // What is handed to roscpp per output since its I/O thread last came round (hand_over_bound.h).
  IoRounds io_rounds_;
  IoRoundsListener io_listener_{io_rounds_};  // destroyed first of the two
  HandOverBound tf_bound_, imu_bound_, state_bound_;
  std::uint64_t outputs_dropped_at_diagnosis_ = 0;
  std::unique_ptr<AttitudeEngine> engine_;
  std::optional<OutputEncoder> encoder_;  // rebuilt when the frames or the integrator change
  bool sim_time_ = false;

  // The decoders (each topic's type, the rates' mount) and tf for them: the listener is
  // created at the first lookup and dropped once the mount is known (unless torque input may
  // need it), so the node does not digest its own /tf stream.
  std::optional<InputDecoders> decoders_;
  std::optional<FixInput> fixes_;
  class TfFrames : public FrameSource {
   public:
    explicit TfFrames(AttitudePropagatorRos& node) : node_(node) {}
    std::optional<Eigen::Quaterniond> rotation(const std::string& target, const std::string& source,
                                               const ros::Time& stamp, std::string* error) override;

   private:
    AttitudePropagatorRos& node_;
  } tf_frames_{*this};
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  bool rates_settled_ = false;  // the latest rate was taken: its mount kept, or none needed
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  ros::Subscriber rate_sub_;
  ros::Subscriber torque_sub_;
  ros::Subscriber clock_sub_;
  ros::Subscriber mag_sub_;
  ros::Subscriber bias_sub_;
  ros::Subscriber fix_sub_;
  ros::Subscriber tf_watch_sub_;
  ros::Subscriber tf_static_watch_sub_;
  TfConflictWatch tf_watch_;
  ros::Publisher tf_pub_;
  ros::Publisher tf_static_pub_;
  ros::Publisher imu_pub_;
  ros::Publisher state_pub_;
  ros::ServiceServer reset_srv_;
  ros::ServiceServer set_state_srv_;
  ros::Timer dynamic_timer_;
  ros::WallTimer watchdog_timer_;
  ros::WallTimer fix_type_timer_;  // asks the master for the fix topic's type (fix_input.h)

  diagnostic_updater::Updater updater_;
  std::unique_ptr<dynamic_reconfigure::Server<AttitudePropagatorConfig>> reconfigure_server_;
  NodeDiagnostics diagnostics_;
  std::uint64_t callback_errors_ = 0;
  // The publishers of the latest /clock tick and of the one before from another publisher:
  // named when ROS time takes turns between two timelines.
  std::string clock_publisher_, previous_clock_publisher_;
};

}  // namespace attitude_propagator
