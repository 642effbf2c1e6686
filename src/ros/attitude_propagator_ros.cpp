#include "attitude_propagator/ros/attitude_propagator_ros.h"

#include <exception>
#include <stdexcept>
#include <string>

#include <boost/make_shared.hpp>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/messages/aiding_counters.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/imu_input.h"
#include "attitude_propagator/messages/input_roles.h"
#include "attitude_propagator/messages/outputs.h"
#include "attitude_propagator/messages/set_state_request.h"
#include "attitude_propagator/ros/input_text.h"
#include "attitude_propagator/ros/live_parameters.h"
#include "attitude_propagator/ros/log_text.h"
#include "attitude_propagator/ros/model_text.h"
#include "attitude_propagator/ros/node_queues.h"
#include "attitude_propagator/ros/note_text.h"
#include "attitude_propagator/ros/parameter_loader.h"

namespace attitude_propagator {

AttitudePropagatorRos::AttitudePropagatorRos(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      imu_nh_(nh, "imu"),
      log_(instancePrefix(pnh.getNamespace(), ros::this_node::getName())),
      in_manager_(!log_.prefix().empty()),
      config_(loadParameters(pnh, log_.prefix())),
      tf_bound_(io_rounds_, static_cast<std::uint64_t>(config_.parameters.output_queue_size)),
      imu_bound_(io_rounds_, static_cast<std::uint64_t>(config_.parameters.output_queue_size)),
      state_bound_(io_rounds_, static_cast<std::uint64_t>(config_.parameters.output_queue_size)),
      updater_(nh, pnh, pnh.getNamespace()),
      diagnostics_(ros::WallTime::now()) {
  refuseFeedbackLoops();
  engine_ = std::make_unique<AttitudeEngine>(engineConfig(config_), *this);
  decoders_.emplace(DecoderFrames::of(config_));
  fixes_.emplace(config_, log_);
  rebuildEncoder();
  sim_time_ = ros::Time::isSimTime();
  advertise();
  publishConventionFrames();
  // Listening from the start: a mount (or a torque's frame) sent before the first message that
  // needs it is heard, as propagate_bag reads a bag's /tf from its start.
  ensureTfListener();
  subscribe();
  updater_.setHardwareID(config_.parameters.body_frame + " from " +
                         (config_.rate_input == RateInput::Imu     ? imu_nh_.resolveName("data_raw")
                          : config_.rate_input == RateInput::Twist ? nh_.resolveName("body_twist")
                                                                   : std::string("no rate input")));
  updater_.add("state", this, &AttitudePropagatorRos::diagnose);
  watchdog_timer_ = nh_.createWallTimer(ros::WallDuration(kWatchdogPeriod),
                                        &AttitudePropagatorRos::onWatchdog, this);
  fix_type_timer_ = nh_.createWallTimer(
      ros::WallDuration(kFixTypeCheckPeriod),
      boost::function<void(const ros::WallTimerEvent&)>([this](const ros::WallTimerEvent&) {
        guarded("fix type check",
                [&] { fixes_->checkRegisteredType(nh_.resolveName("orientation_fix")); });
      }));
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<AttitudePropagatorConfig>>(pnh_);
  reconfigure_server_->setCallback(
      [this](AttitudePropagatorConfig& live, std::uint32_t level) { onReconfigure(live, level); });
  if (engine_->dynamicModel()) {
    dynamic_timer_ = nh_.createTimer(ros::Duration(1.0 / config_.parameters.publish_rate),
                                     &AttitudePropagatorRos::onDynamicTimer, this);
  }
  writeResolved();
  logModel();
}

AttitudePropagatorRos::~AttitudePropagatorRos() = default;

void AttitudePropagatorRos::refuseFeedbackLoops() const {
  const std::vector<NamedTopic> outputs{{"imu/data", imu_nh_.resolveName("data")},
                                        {"attitude_state", nh_.resolveName("attitude_state")}};
  std::vector<NamedTopic> inputs;
  for (const InputRoleRow& row : inputRoleTable()) {
    if (subscribed(row, config_)) inputs.push_back({row.topic, nh_.resolveName(row.topic)});
  }
  if (const auto loop = feedbackLoop(outputs, inputs)) throw std::invalid_argument(*loop);
}

void AttitudePropagatorRos::advertise() {
  // Published as shared pointers so subscribers in the same nodelet manager get them without
  // a copy. The tf publisher is our own (tf2_ros::TransformBroadcaster publishes by value).
  const auto queue = static_cast<std::uint32_t>(config_.parameters.output_queue_size);
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", queue);
  if (config_.world != WorldConvention::Enu) {
    tf_static_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf_static", 1, true);
  }
  imu_pub_ = imu_nh_.advertise<sensor_msgs::Imu>("data", queue);
  state_pub_ = nh_.advertise<AttitudeState>("attitude_state", queue);
  reset_srv_ = pnh_.advertiseService("reset", &AttitudePropagatorRos::onReset, this);
  set_state_srv_ = pnh_.advertiseService("set_state", &AttitudePropagatorRos::onSetState, this);
}

void AttitudePropagatorRos::subscribe() {
  const auto hints = ros::TransportHints().tcpNoDelay();
  const auto queue = static_cast<std::uint32_t>(config_.parameters.input_queue_size);
  // Which topics: input_roles.h (the feedback-loop check reads the same).
  auto takes = [this](const InputRoleRow& row) { return subscribed(row, config_); };
  if (takes(inputRoleOf(Source::Imu))) {
    rate_sub_ = imu_nh_.subscribe("data_raw", queue, &AttitudePropagatorRos::onImu, this, hints);
  } else if (takes(inputRoleOf(Source::Twist))) {
    rate_sub_ = nh_.subscribe("body_twist", queue, &AttitudePropagatorRos::onTwist, this, hints);
  }
  if (takes(inputRoleOf(InputRole::Field))) {
    mag_sub_ = imu_nh_.subscribe("mag", queue, &AttitudePropagatorRos::onMag, this, hints);
  }
  if (takes(inputRoleOf(Source::Torque))) {
    torque_sub_ = nh_.subscribe("torque", queue, &AttitudePropagatorRos::onTorque, this, hints);
  }
  if (takes(inputRoleOf(InputRole::Bias))) {
    bias_sub_ = nh_.subscribe("gyro_bias", kSparseQueueSize, &AttitudePropagatorRos::onGyroBias,
                              this, hints);
  }
  fix_sub_ = nh_.subscribe("orientation_fix", kSparseQueueSize, &AttitudePropagatorRos::onFix, this,
                           hints);
  watchTf();
  if (sim_time_) {
    // Under sim time /clock is the time source: every tick is seen, in order with the inputs
    // on this queue, so a jump of the clock is told apart from a callback that ran late.
    clock_sub_ = nh_.subscribe<rosgraph_msgs::Clock>(
        "/clock", queue,
        boost::function<void(const ros::MessageEvent<const rosgraph_msgs::Clock>&)>(
            [this](const ros::MessageEvent<const rosgraph_msgs::Clock>& e) { onClock(e); }),
        ros::VoidConstPtr(), hints);
  }
}

void AttitudePropagatorRos::watchTf() {
  const auto& p = config_.parameters;
  if (!p.publish_tf || p.tf_conflict == "ignore") {
    tf_watch_sub_.shutdown();
    tf_static_watch_sub_.shutdown();
    return;
  }
  if (tf_watch_sub_) return;
  using TfEvent = ros::MessageEvent<const tf2_msgs::TFMessage>;
  tf_watch_sub_ = nh_.subscribe<tf2_msgs::TFMessage, const TfEvent&>(
      "/tf", kTfWatchQueueSize,
      boost::function<void(const TfEvent&)>([this](const TfEvent& e) { onTfSeen(e, false); }));
  tf_static_watch_sub_ = nh_.subscribe<tf2_msgs::TFMessage, const TfEvent&>(
      "/tf_static", kSparseQueueSize,
      boost::function<void(const TfEvent&)>([this](const TfEvent& e) { onTfSeen(e, true); }));
}

void AttitudePropagatorRos::rebuildEncoder() { encoder_.emplace(config_, *engine_); }

void AttitudePropagatorRos::publishConventionFrames() {
  if (!tf_static_pub_) return;
  auto msg = boost::make_shared<tf2_msgs::TFMessage>();
  // Stamped now, as tf2_ros's static broadcaster does: a static transform holds at every time.
  msg->transforms = encoder_->conventionFrames(ros::Time::now());
  tf_static_pub_.publish(msg);
}

void AttitudePropagatorRos::writeResolved() const {
  pnh_.setParam("resolved_model", modelName(config_.model));
  pnh_.setParam("resolved_integrator", integratorName(engine_->integrator()));
}

void AttitudePropagatorRos::logModel() {
  log(LogLine{ros::console::levels::Info, "", modelText(config_, *engine_)});
}

template <class F>
void AttitudePropagatorRos::guarded(const char* where, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    ++callback_errors_;
    // The text may quote a message's strings (tf's errors quote frame ids).
    // Throttled per callback: an error in one never hides another's.
    log(LogLine{ros::console::levels::Error, std::string("callback error ") + where,
                formatted("%s: %s (input ignored, %lu errors so far)", where,
                          logText(e.what(), 4 * kLogTextBytes).c_str(), callback_errors_)});
  } catch (...) {
    ++callback_errors_;
    log(LogLine{ros::console::levels::Error, std::string("callback error ") + where,
                formatted("%s: unknown exception (input ignored)", where)});
  }
}

void AttitudePropagatorRos::log(const std::optional<LogLine>& line) {
  log_.log(line, ros::WallTime::now().toSec(), kWarnPeriod);
}

// --- Inputs: decoded by the message layer (input_decoders.h), counted, logged, submitted

std::optional<Eigen::Quaterniond> AttitudePropagatorRos::TfFrames::rotation(
    const std::string& target, const std::string& source, const ros::Time& stamp,
    std::string* error) {
  node_.ensureTfListener();
  return BufferCoreFrames(*node_.tf_buffer_).rotation(target, source, stamp, error);
}

void AttitudePropagatorRos::onImu(const ros::MessageEvent<const sensor_msgs::Imu>& event) {
  guarded("imu/data_raw", [&] {
    pollClock();
    const sensor_msgs::Imu::ConstPtr& msg = event.getConstMessage();
    DecodedInput in = decoders_->imu(*msg, event.getReceiptTime(), &tf_frames_);
    if (!taken(in, "imu/data_raw")) return;
    if (imu_pub_.getNumSubscribers() > 0) {
      in.value->payload = std::make_shared<ImuPayload>(ImuPayload{msg, in.q_BS});
    }
    submit(*in.value);
    // The accelerometer after the rate of its own message, at the same stamp: the rates have
    // reached it, so it is applied now (counted in accel_*).
    if (config_.parameters.use_accel && in.acceleration) {
      engine_->submitAcceleration(in.acceleration->stamp, in.acceleration->value_B,
                                  in.acceleration->covariance_B);
    }
  });
}

void AttitudePropagatorRos::onMag(
    const ros::MessageEvent<const sensor_msgs::MagneticField>& event) {
  guarded("imu/mag", [&] {
    pollClock();
    const DecodedField field =
        decoders_->magneticField(*event.getConstMessage(), event.getReceiptTime(), &tf_frames_);
    warnFrames();
    if (field.refusal) return refused(*field.refusal, "imu/mag");
    if (field.new_mount) {
      const Eigen::Quaterniond& q = decoders_->magMount();
      log(LogLine{ros::console::levels::Info, "",
                  formatted("imu/mag: the field in frame '%s' is rotated into '%s' by q = [%g, "
                            "%g, %g, %g] (x y z w)",
                            logText(decoders_->magFrame()).c_str(),
                            config_.parameters.body_frame.c_str(), q.x(), q.y(), q.z(), q.w())});
    }
    releaseTfListener(rates_settled_);
    engine_->submitMagneticField(field->stamp, field->value_B, field->covariance_B);
  });
}

void AttitudePropagatorRos::onTwist(
    const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  guarded("body_twist", [&] {
    pollClock();
    const DecodedInput in =
        decoders_->twistTopic(*event.getConstMessage(), event.getReceiptTime(), &tf_frames_);
    if (taken(in, "body_twist")) submit(*in.value);
  });
}

void AttitudePropagatorRos::onTorque(
    const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  guarded("torque", [&] {
    pollClock();
    const DecodedInput in =
        decoders_->torqueTopic(*event.getConstMessage(), event.getReceiptTime(), &tf_frames_);
    if (taken(in, "torque")) submit(*in.value);
  });
}

void AttitudePropagatorRos::onGyroBias(const geometry_msgs::Vector3Stamped::ConstPtr& msg) {
  guarded("gyro_bias", [&] {
    // Unstamped: from now on (ROS time; zero before the first /clock: from the start).
    const Decoded<BiasSample> bias = decoders_->bias(*msg, ros::Time::now());
    warnFrames();
    if (!bias) return refused(*bias.refusal, "gyro_bias");
    if (!engine_->submitBias(bias->stamp, bias->b_B)) log(biasRejectedText(engine_->counters()));
  });
}

void AttitudePropagatorRos::onFix(const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  guarded("orientation_fix", [&] {
    pollClock();
    fixes_->onMessage(*event.getConstMessage(), event.getReceiptTime(), event.getPublisherName(),
                      *engine_, tf_frames_);
  });
}

void AttitudePropagatorRos::onClock(const ros::MessageEvent<const rosgraph_msgs::Clock>& event) {
  guarded("/clock", [&] {
    const std::string& publisher = event.getPublisherName();
    if (publisher != clock_publisher_) {
      previous_clock_publisher_ = clock_publisher_;
      clock_publisher_ = publisher;
    }
    engine_->clockTick(toStamp(event.getConstMessage()->clock));
  });
}

void AttitudePropagatorRos::submit(const Input& input) {
  diagnostics_.inputArrived(ros::WallTime::now());
  engine_->submit(input);
}

void AttitudePropagatorRos::warnFrames() {
  // Once per frame with tf1's leading '/' (frame_ids.h): read without it.
  for (const auto& w : decoders_->takeFrameWarnings()) {
    log(LogLine{ros::console::levels::Warn, "", logText(w, 4 * kLogTextBytes)});
  }
}

bool AttitudePropagatorRos::taken(const DecodedInput& in, const char* topic) {
  warnFrames();
  if (in.refusal) {
    // Rates waiting for their mount keep the listener (the field's callback may not drop it).
    if (in.refusal->why == Refused::NoTransform) rates_settled_ = false;
    refused(*in.refusal, topic);
    return false;
  }
  if (in.new_mount) {
    log(LogLine{ros::console::levels::Info, "",
                mountText(decoders_->mountFrame(), config_.parameters.body_frame, in.q_BS)});
  }
  rates_settled_ = true;
  releaseTfListener(in.new_mount || decoders_->mountFrame().empty());
  return true;
}

void AttitudePropagatorRos::releaseTfListener(bool mount_settled) {
  // The mount is cached (or the rates need none), and the field's too when it comes: stop
  // listening, or the listener would keep digesting our own /tf. Rates or a field in a new
  // frame later start it again (ensureTfListener).
  const bool mag_settled = !config_.parameters.use_mag || decoders_->magSettled();
  if (tf_buffer_ && mount_settled && mag_settled && !config_.torque_input && !fixes_->usesTf()) {
    tf_listener_.reset();
    tf_buffer_.reset();
  }
}

void AttitudePropagatorRos::refused(const Refusal& r, const char* topic) {
  countRefusal(*engine_, r.why);
  const auto line =
      refusalText(r, topic, engine_->counters(), config_.parameters.body_frame, *decoders_);
  const std::string name = topic;
  if (line && name != "gyro_bias" && name != "torque" && name != "imu/mag") {
    // Named in the diagnostics while no rate gets through (node_diagnostics.h).
    diagnostics_.inputRefused(ros::WallTime::now(), line->text);
  }
  log(line);
}

void AttitudePropagatorRos::ensureTfListener() {
  if (tf_buffer_) return;
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
}

// --- Time

void AttitudePropagatorRos::pollClock() {
  if (!sim_time_) engine_->poll(toStamp(ros::Time::now()));
}

void AttitudePropagatorRos::onDynamicTimer(const ros::TimerEvent&) {
  guarded("publish timer", [&] { pollClock(); });
}

void AttitudePropagatorRos::onWatchdog(const ros::WallTimerEvent&) {
  guarded("watchdog", [&] {
    if (sim_time_) {
      // Not the clock itself: /clock ticks may still wait in the queue behind this callback,
      // and reading ros::Time::now() here would take them for a jump.
      engine_->drain();  // catches up after a call that ran out of budget
    } else {
      pollClock();
    }
    log(tf_watch_.resumeTfIfClear(config_.parameters, ros::WallTime::now()));
    diagnostics_.closeInputWindow(ros::WallTime::now(), *engine_, config_.parameters.max_dt);
    if ((ros::WallTime::now() - diagnostics_.lastDiagnosis()).toSec() >= updater_.getPeriod()) {
      updater_.force_update();
    }
  });
}

// --- Outputs

void AttitudePropagatorRos::publishState(const EngineState& state) {
  if (config_.parameters.publish_tf) publishTf(state);
  if (state_pub_.getNumSubscribers() == 0) return;
  if (!handOver(state_bound_)) return;
  auto msg = boost::make_shared<AttitudeState>();
  encoder_->state(state, *msg);
  state_pub_.publish(msg);
}

void AttitudePropagatorRos::inputApplied(const Input& input, const EngineState& state) {
  if (!input.payload) return;
  const auto& imu = *std::static_pointer_cast<const ImuPayload>(input.payload);
  publishImu(*imu.msg, state, imu.q_BS);
}

void AttitudePropagatorRos::note(const EngineNote& note) {
  if (note.kind == EngineNote::ClockTwoTimelines) {
    // The tick that returned to the later timeline is the latest; the one before it, from
    // another publisher, the earlier timeline's (one publisher alternating: no other).
    diagnostics_.clockSources(clockPublishersText(clock_publisher_, previous_clock_publisher_));
  }
  log(noteText(note, engine_->counters(), config_.parameters, engine_->dynamicModel(),
               diagnostics_.clockSources()));
}

void AttitudePropagatorRos::onTfSeen(const ros::MessageEvent<const tf2_msgs::TFMessage>& event,
                                     bool latched) {
  guarded(latched ? "/tf_static watch" : "/tf watch", [&] {
    const bool named_like_us = event.getPublisherName() == ros::this_node::getName();
    if (named_like_us && !in_manager_) return;  // our own: a node of its own
    log(tf_watch_.onTfSeen(*event.getConstMessage(), event.getPublisherName(), named_like_us,
                           latched, config_.parameters, ros::WallTime::now()));
  });
}

void AttitudePropagatorRos::publishTf(const EngineState& state) {
  if (tf_watch_.stopped() || !handOver(tf_bound_)) return;
  auto msg = boost::make_shared<tf2_msgs::TFMessage>();
  msg->transforms.resize(1);
  encoder_->transform(state, msg->transforms[0]);
  if (in_manager_ && tf_watch_sub_) tf_watch_.sent(msg->transforms[0]);
  tf_pub_.publish(msg);
}

void AttitudePropagatorRos::publishImu(const sensor_msgs::Imu& input, const EngineState& state,
                                       const Eigen::Quaterniond& q_BS) {
  if (imu_pub_.getNumSubscribers() == 0 || !handOver(imu_bound_)) return;
  auto msg = boost::make_shared<sensor_msgs::Imu>();
  encoder_->imu(input, state, q_BS, *msg);
  imu_pub_.publish(msg);
}

// --- Services and diagnostics

bool AttitudePropagatorRos::onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  guarded("~reset", [&] {
    engine_->reset();
    log(LogLine{ros::console::levels::Info, "reset",
                formatted("reset to the initial state; the next input anchors time (%lu resets "
                          "so far)",
                          engine_->counters().resets)});
  });
  return true;
}

bool AttitudePropagatorRos::onSetState(SetState::Request& request, SetState::Response& response) {
  response.success = false;
  guarded("~set_state", [&] {
    pollClock();
    applySetState(request, ros::Time::now(), config_.world, *engine_, response);
  });
  return true;
}

void AttitudePropagatorRos::onReconfigure(AttitudePropagatorConfig& live, std::uint32_t) {
  const Parameters p = liveParameters(config_.parameters, live);
  const LiveChange change = liveChange(config_.parameters, p);
  std::string error;
  guarded("reconfigure", [&] {
    error = applyLive(p, change, *engine_, config_);
    if (!error.empty()) return;
    rebuildEncoder();
    // Switching publish_tf off and on says "look again": the stop is lifted, and the watch,
    // subscribed anew, gets the latched /tf_static parents still published (which stop tf
    // again). reverse_tf changes our child frame, so the old conflict is not ours any more.
    if (change.tf_toggled || change.child_changed) {
      if (p.publish_tf) {
        log(tf_watch_.resumeTf(change.tf_toggled ? "publish_tf switched off and on"
                                                 : "reverse_tf changed our child frame",
                               config_.parameters));
      }
      tf_watch_sub_.shutdown();
      tf_static_watch_sub_.shutdown();
      watchTf();
    }
    if (change.engine_changes) writeResolved();
  });
  log(reconfigureText(error, change.engine_changes, config_.parameters, engine_->integrator()));
  showInForce(config_.parameters, live);
}

std::uint64_t AttitudePropagatorRos::outputsDropped() const {
  return tf_bound_.dropped() + imu_bound_.dropped() + state_bound_.dropped();
}

bool AttitudePropagatorRos::handOver(HandOverBound& bound) {
  if (bound.admit()) return true;
  log(LogLine{ros::console::levels::Warn, "outputs dropped",
              formatted("outputs dropped: roscpp's I/O thread has not come round for %d messages "
                        "of an output (it is kept reading an input faster than it can); the "
                        "newest are dropped so that memory stays bounded (output_queue_size; %lu "
                        "so far)",
                        config_.parameters.output_queue_size,
                        static_cast<unsigned long>(outputsDropped()))});
  return false;
}

void AttitudePropagatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  diagnostics_.diagnose(ros::WallTime::now(), config_, *engine_, *fixes_, tf_watch_,
                        callback_errors_, status);
  const std::uint64_t dropped = outputsDropped();
  status.add("outputs_dropped", dropped);
  if (dropped > outputs_dropped_at_diagnosis_) {
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN,
                        "outputs dropped: roscpp's I/O thread is kept reading input faster than "
                        "it can (output_queue_size bounds what waits for it)");
  }
  outputs_dropped_at_diagnosis_ = dropped;
}

}  // namespace attitude_propagator
