#include "attitude_propagator/ros/attitude_propagator_ros.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include <boost/make_shared.hpp>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/ros/log_text.h"
#include "attitude_propagator/ros/parameter_loader.h"

namespace attitude_propagator {

namespace {

// Every queue the node sets is bounded in messages: at most the queue size times the size of
// one message, per queue. (roscpp's hand-over from publish() to its I/O thread is not ours to
// bound: it grows while that thread is kept reading an input faster than it can.)
// Inputs are queued, not dropped, through a burst of this many messages (a bag played fast,
// a load generator); beyond it roscpp drops the oldest.
constexpr std::uint32_t kInputQueueSize = 10000;
// Per subscriber connection: a burst of a few thousand reaches a subscriber that keeps reading
// (kinematic.test sends 3000 to a Python subscriber; with 1000 here it lost some), while one
// that falls further behind (a slow remote reader) loses the oldest messages. The node holds up
// to this many per output and slow subscriber: one slow subscriber of all three outputs held it
// at 82 MB with 10 000 (IMU input at 31 kHz), at 31 MB with 5 000. Subscribers in the same
// nodelet manager are served through their own queue.
constexpr std::uint32_t kOutputQueueSize = 5000;
// The tf watch needs one message of a conflicting publisher, not every transform on /tf.
constexpr std::uint32_t kTfWatchQueueSize = 1000;
// Topics with a message now and then (gyro bias, /tf_static).
constexpr std::uint32_t kSparseQueueSize = 100;
// Throttle period (s) of warnings about input that keeps coming bad.
constexpr double kWarnPeriod = 5.0;
// How often the clock is looked at while nothing else happens (wall seconds): publishes a
// grid stamp the timer missed, notices a clock that went back, updates diagnostics.
constexpr double kWatchdogPeriod = 0.1;
// tf stopped by a conflict on /tf resumes after this long (wall s) without another parent of
// our child frame there: tf publishers repeat their transforms at 10 Hz or more, so 2 s is
// many missed messages, not a pause between two.
constexpr double kTfConflictClearance = 2.0;
// Diagnostics judge what became of the rate samples over windows of this long (wall s).
constexpr double kInputWindow = 1.0;

/// An IMU message kept with an input until the engine applies it, and its sensor mount.
struct ImuPayload {
  sensor_msgs::Imu::ConstPtr msg;
  Eigen::Quaterniond q_BS;
};

}  // namespace

AttitudePropagatorRos::AttitudePropagatorRos(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      imu_nh_(nh, "imu"),
      config_(loadParameters(pnh)),
      updater_(nh, pnh, pnh.getNamespace()) {
  engine_ = std::make_unique<AttitudeEngine>(engineConfig(config_), *this);
  decoders_.emplace(DecoderFrames::of(config_));
  fixes_.emplace(config_);
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
  last_diagnosis_ = ros::WallTime::now();
  watchdog_timer_ = nh_.createWallTimer(ros::WallDuration(kWatchdogPeriod),
                                        &AttitudePropagatorRos::onWatchdog, this);
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

void AttitudePropagatorRos::advertise() {
  // Published as shared pointers so subscribers in the same nodelet manager get them without
  // a copy. The tf publisher is our own (tf2_ros::TransformBroadcaster publishes by value).
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", kOutputQueueSize);
  if (config_.world != WorldConvention::Enu) {
    tf_static_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf_static", 1, true);
  }
  imu_pub_ = imu_nh_.advertise<sensor_msgs::Imu>("data", kOutputQueueSize);
  state_pub_ = nh_.advertise<AttitudeState>("attitude_state", kOutputQueueSize);
  reset_srv_ = pnh_.advertiseService("reset", &AttitudePropagatorRos::onReset, this);
  set_state_srv_ = pnh_.advertiseService("set_state", &AttitudePropagatorRos::onSetState, this);
}

void AttitudePropagatorRos::subscribe() {
  const auto hints = ros::TransportHints().tcpNoDelay();
  if (config_.rate_input == RateInput::Imu) {
    rate_sub_ =
        imu_nh_.subscribe("data_raw", kInputQueueSize, &AttitudePropagatorRos::onImu, this, hints);
  } else if (config_.rate_input == RateInput::Twist) {
    rate_sub_ =
        nh_.subscribe("body_twist", kInputQueueSize, &AttitudePropagatorRos::onTwist, this, hints);
  }
  if (engine_->dynamicModel() && config_.torque_input) {
    torque_sub_ =
        nh_.subscribe("torque", kInputQueueSize, &AttitudePropagatorRos::onTorque, this, hints);
  }
  if (config_.rate_input != RateInput::None) {
    bias_sub_ = nh_.subscribe("gyro_bias", kSparseQueueSize, &AttitudePropagatorRos::onGyroBias,
                              this, hints);
  }
  fix_sub_ = nh_.subscribe("orientation_fix", kSparseQueueSize, &AttitudePropagatorRos::onFix, this,
                           hints);
  watchTf();
  if (sim_time_) {
    // Under sim time /clock is the time source: every tick is seen, in order with the inputs
    // on this queue, so a jump of the clock is told apart from a callback that ran late.
    clock_sub_ =
        nh_.subscribe("/clock", kInputQueueSize, &AttitudePropagatorRos::onClock, this, hints);
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

void AttitudePropagatorRos::logModel() const {
  const auto& p = config_.parameters;
  if (engine_->dynamicModel()) {
    ROS_INFO(
        "attitude_propagator: dynamic model %s (integrator %s, max_step %g s), "
        "publishing %s -> %s at %g Hz; rate input %s, torque input %s",
        engine_->modelName().c_str(), integratorName(engine_->integrator()).c_str(),
        config_.dynamic->max_step, p.fixed_frame.c_str(), p.body_frame.c_str(), p.publish_rate,
        p.rate_input.c_str(), config_.torque_input ? "on" : "off");
  } else {
    ROS_INFO(
        "attitude_propagator: kinematic model (integrator %s), publishing %s -> %s per "
        "%s message",
        integratorName(engine_->integrator()).c_str(), p.fixed_frame.c_str(), p.body_frame.c_str(),
        p.rate_input.c_str());
  }
}

template <class F>
void AttitudePropagatorRos::guarded(const char* where, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    ++callback_errors_;
    // The text may quote a message's strings (tf's errors quote frame ids).
    ROS_ERROR_THROTTLE(kWarnPeriod, "%s: %s (input ignored, %lu errors so far)", where,
                       logText(e.what(), 4 * kLogTextBytes).c_str(), callback_errors_);
  } catch (...) {
    ++callback_errors_;
    ROS_ERROR_THROTTLE(kWarnPeriod, "%s: unknown exception (input ignored)", where);
  }
}

// ---------------------------------------------------------------------------------------------
// Inputs: the message layer decodes (input_decoders.h); here they are counted, logged, submitted
// ---------------------------------------------------------------------------------------------

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
    if (!bias) return refused(*bias.refusal, "gyro_bias");
    if (!engine_->submitBias(bias->stamp, bias->b_B)) {
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "gyro_bias: non-finite or larger than %g rad/s: rejected (%lu so far)",
                        kMaxBodyRate, engine_->counters().rejected_bias);
    }
  });
}

void AttitudePropagatorRos::onFix(const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  guarded("orientation_fix", [&] {
    pollClock();
    fixes_->onMessage(*event.getConstMessage(), event.getReceiptTime(), *engine_, tf_frames_);
  });
}

void AttitudePropagatorRos::onClock(const rosgraph_msgs::Clock::ConstPtr& msg) {
  guarded("/clock", [&] { engine_->clockTick(toStamp(msg->clock)); });
}

void AttitudePropagatorRos::submit(const Input& input) {
  last_input_ = ros::WallTime::now();
  engine_->submit(input);
}

bool AttitudePropagatorRos::taken(const DecodedInput& in, const char* topic) {
  if (in.refusal) {
    refused(*in.refusal, topic);
    return false;
  }
  if (in.new_mount) {
    const std::string& body = config_.parameters.body_frame;
    const Eigen::Quaterniond& q = in.q_BS;
    ROS_INFO("rates in frame '%s' are rotated into '%s' by q = [%g, %g, %g, %g] (x y z w)",
             logText(decoders_->mountFrame()).c_str(), body.c_str(), q.x(), q.y(), q.z(), q.w());
  }
  const bool mount_settled = in.new_mount || decoders_->mountFrame().empty();
  if (tf_buffer_ && mount_settled && !config_.torque_input && !fixes_->usesTf()) {
    // The mount is cached (or the rates need none): stop listening, or the listener would keep
    // digesting our own /tf. Rates in a new frame later start it again (ensureTfListener).
    tf_listener_.reset();
    tf_buffer_.reset();
  }
  return true;
}

void AttitudePropagatorRos::refused(const Refusal& r, const char* topic) {
  countRefusal(*engine_, r.why);
  const EngineCounters& c = engine_->counters();
  const std::string& body = config_.parameters.body_frame;
  const bool torque = std::strcmp(topic, "torque") == 0;
  switch (r.why) {
    case Refused::NoRate:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: angular_velocity_covariance[0] == -1 (no rate, REP-145): rejected "
                        "(%lu so far)",
                        topic, c.rejected_no_rate);
      break;
    case Refused::BadCovariance:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: angular_velocity_covariance rejected (%s; accepted: symmetric, "
                        "variances in [0, %g] rad^2/s^2) (%lu so far)",
                        topic, rateCovarianceCheckName(r.check), kMaxRateVariance,
                        c.rejected_covariance);
      break;
    case Refused::WrongType: {
      const TopicType& type = torque ? decoders_->torqueType() : decoders_->twistType();
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: message type %s rejected; the topic carries %s (its first "
                        "message's type; accepted: %s or %s) (%lu rejected so far)",
                        topic, logText(r.detail).c_str(),
                        type.datatype().empty() ? "nothing yet" : type.datatype().c_str(),
                        type.plainType().c_str(), type.stampedType().c_str(), c.rejected_type);
      break;
    }
    case Refused::NoTransform:
      if (torque) {
        ROS_WARN_THROTTLE(
            kWarnPeriod, "torque in frame '%s': no transform to '%s' yet: dropped (%s)",
            logText(r.frame).c_str(), body.c_str(), logText(r.detail, 4 * kLogTextBytes).c_str());
      } else {
        ROS_WARN_THROTTLE(kWarnPeriod,
                          "rates in frame '%s': waiting for the static transform from '%s'; "
                          "dropped %lu messages so far (%s)",
                          logText(r.frame).c_str(), body.c_str(), c.dropped_no_tf,
                          logText(r.detail, 4 * kLogTextBytes).c_str());
      }
      break;
    case Refused::NoTime:
      // An unstamped message under sim time before the first /clock: no time to put it at.
      ROS_WARN_THROTTLE(kWarnPeriod, "%s: unstamped message and no ROS time yet (/clock): dropped",
                        topic);
      break;
    case Refused::BiasFrame:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "gyro_bias: frame '%s' rejected; accepted: '%s' (the body), the rate "
                        "messages' frame once known, or empty (%lu rejected so far)",
                        logText(r.frame).c_str(), body.c_str(), c.rejected_bias);
      break;
    case Refused::NoOrientation:
      break;  // fixes only: fix_input.cpp logs them
  }
}

void AttitudePropagatorRos::ensureTfListener() {
  if (tf_buffer_) return;
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
}

// ---------------------------------------------------------------------------------------------
// Time
// ---------------------------------------------------------------------------------------------

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
    resumeTfIfClear();
    closeInputWindow();
    if ((ros::WallTime::now() - last_diagnosis_).toSec() >= updater_.getPeriod()) {
      updater_.force_update();
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

void AttitudePropagatorRos::publishState(const EngineState& state) {
  if (config_.parameters.publish_tf) publishTf(state);
  if (state_pub_.getNumSubscribers() == 0) return;
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
  const char* what = note.source ? sourceName(*note.source) : "ROS time";
  const double t = static_cast<double>(note.stamp) * 1e-9;
  const EngineCounters& c = engine_->counters();
  // One throttled line per kind, so a flood of one kind never hides another.
  switch (note.kind) {
    case EngineNote::Gap:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: gap longer than max_dt = %g s before %.6f: not integrated across, "
                        "state held (%lu gaps so far)",
                        what, config_.parameters.max_dt, t, c.gaps);
      break;
    case EngineNote::StampsJumpedBack:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: stamps jumped back to %.3f and went on from there (looped bag, "
                        "restarted driver?): %s (%lu jumps so far)",
                        what, t,
                        engine_->dynamicModel() ? "its inputs now act late, on ROS time"
                                                : "reset to the initial state",
                        c.jumps_back);
      break;
    case EngineNote::Future:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: stamp %.6f more than max_future = %g s ahead of ROS time: rejected "
                        "(%lu so far; unsynchronised clocks?)",
                        what, t, config_.parameters.max_future, c.rejected_future);
      break;
    case EngineNote::ClockJumpedBack:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "ROS time jumped back to %.3f s (looped bag or restarted clock): reset "
                        "to the initial state (%lu resets so far)",
                        t, c.resets);
      break;
    case EngineNote::Stale:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: stamp %.6f at or before the last one: dropped (%lu so far)", what, t,
                        c.dropped_stale);
      break;
    case EngineNote::NonFinite:
      ROS_WARN_THROTTLE(kWarnPeriod, "%s: NaN or infinite value or stamp: rejected (%lu so far)",
                        what, c.rejected_non_finite);
      break;
    case EngineNote::OutOfRange:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: value out of the accepted range (its energy or step would "
                        "overflow): rejected (%lu so far)",
                        what, c.rejected_out_of_range);
      break;
    case EngineNote::FailedStep:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: the integrator could not complete the step to %.6f: state held "
                        "(%lu failed so far)",
                        what, t, c.failed_steps);
      break;
    case EngineNote::PendingFull:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: more inputs stamped ahead of ROS time than the queue holds: the "
                        "one stamped furthest ahead dropped (%lu so far)",
                        what, c.pending_overflow);
      break;
    case EngineNote::Deferred:
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "publishing fell behind ROS time at %.3f s: the rest of the grid follows "
                        "on the next tick (%lu so far)",
                        t, c.deferred_ticks);
      break;
  }
}

void AttitudePropagatorRos::onTfSeen(const ros::MessageEvent<const tf2_msgs::TFMessage>& event,
                                     bool latched) {
  guarded(latched ? "/tf_static watch" : "/tf watch", [&] {
    if (event.getPublisherName() == ros::this_node::getName()) return;  // our own
    const auto& p = config_.parameters;
    const std::string& child = p.reverse_tf ? p.fixed_frame : p.body_frame;
    const std::string& parent = p.reverse_tf ? p.body_frame : p.fixed_frame;
    for (const auto& t : event.getConstMessage()->transforms) {
      if (t.child_frame_id != child) continue;
      ++tf_conflicts_;
      const bool stop = p.tf_conflict == "stop";
      if (stop) {
        if (latched) tf_conflict_latched_ = true;
        if (!latched) last_tf_conflict_ = ros::WallTime::now();
      }
      // warn: once. stop: at each stop, so a conflict that comes back is named again.
      if (stop ? !tf_stopped_ : tf_conflicts_ == 1) {
        ROS_WARN(
            "tf: %s also publishes '%s' as the child of '%s' on %s (we publish %s -> %s): a "
            "frame has one parent. Publish our transform to a frame of its own "
            "(body_frame:=%s_attitude), or reverse_tf:=true for a tree rooted at the body, or "
            "publish_tf:=false%s",
            logText(event.getPublisherName()).c_str(), child.c_str(),
            logText(t.header.frame_id).c_str(), latched ? "/tf_static" : "/tf", parent.c_str(),
            child.c_str(), child.c_str(),
            !stop     ? "; tf_conflict:=stop would stop our tf instead"
            : latched ? "; tf_conflict is stop: no tf from this node until publish_tf is "
                        "switched off and on"
                      : "; tf_conflict is stop: no tf from this node until no other parent "
                        "has been seen on /tf for 2 s, or publish_tf is switched off and on");
      }
      if (stop) tf_stopped_ = true;
      return;
    }
  });
}

void AttitudePropagatorRos::resumeTfIfClear() {
  if (!tf_stopped_ || tf_conflict_latched_) return;
  if ((ros::WallTime::now() - last_tf_conflict_).toSec() < kTfConflictClearance) return;
  resumeTf("no other parent on /tf for 2 s");
}

void AttitudePropagatorRos::resumeTf(const char* why) {
  tf_conflict_latched_ = false;
  if (!tf_stopped_) return;
  tf_stopped_ = false;
  ++tf_resumes_;
  const auto& p = config_.parameters;
  ROS_INFO("tf: %s: publishing %s -> %s again", why,
           (p.reverse_tf ? p.body_frame : p.fixed_frame).c_str(),
           (p.reverse_tf ? p.fixed_frame : p.body_frame).c_str());
}

void AttitudePropagatorRos::publishTf(const EngineState& state) {
  if (tf_stopped_) return;
  auto msg = boost::make_shared<tf2_msgs::TFMessage>();
  msg->transforms.resize(1);
  encoder_->transform(state, msg->transforms[0]);
  tf_pub_.publish(msg);
}

void AttitudePropagatorRos::publishImu(const sensor_msgs::Imu& input, const EngineState& state,
                                       const Eigen::Quaterniond& q_BS) {
  if (imu_pub_.getNumSubscribers() == 0) return;
  auto msg = boost::make_shared<sensor_msgs::Imu>();
  encoder_->imu(input, state, q_BS, *msg);
  imu_pub_.publish(msg);
}

// ---------------------------------------------------------------------------------------------
// Services and diagnostics
// ---------------------------------------------------------------------------------------------

bool AttitudePropagatorRos::onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  guarded("~reset", [&] {
    engine_->reset();
    ROS_INFO_THROTTLE(kWarnPeriod,
                      "reset to the initial state; the next input anchors time "
                      "(%lu resets so far)",
                      engine_->counters().resets);
  });
  return true;
}

bool AttitudePropagatorRos::onSetState(SetState::Request& request, SetState::Response& response) {
  response.success = false;
  guarded("~set_state", [&] {
    pollClock();
    const ros::Time stamp = request.header.stamp.isZero() ? ros::Time::now() : request.header.stamp;
    if (stamp.isZero()) {
      response.message = "no ROS time yet (use_sim_time without /clock): give header.stamp";
      return;
    }
    // Given in world_frame's axes, as the state is published.
    const std::string error = engine_->setState(
        toStamp(stamp), attitudeFromConvention(config_.world, toEigen(request.orientation)),
        bodyVectorFromConvention(config_.world, toEigen(request.angular_velocity)));
    response.success = error.empty();
    response.message =
        error.empty() ? "state set at " + std::to_string(stamp.toSec()) + " s" : error;
  });
  return true;
}

void AttitudePropagatorRos::onReconfigure(AttitudePropagatorConfig& live, std::uint32_t) {
  Parameters p = config_.parameters;
  p.angular_velocity_stddev = live.angular_velocity_stddev;
  p.max_dt = live.max_dt;
  p.torque_timeout = live.torque_timeout;
  p.publish_tf = live.publish_tf;
  p.reverse_tf = live.reverse_tf;
  p.integrator = live.integrator;
  const Parameters& now = config_.parameters;
  const bool engine_changes = p.angular_velocity_stddev != now.angular_velocity_stddev ||
                              p.max_dt != now.max_dt || p.torque_timeout != now.torque_timeout ||
                              p.integrator != now.integrator;
  const bool tf_toggled = p.publish_tf != now.publish_tf;
  const bool child_changed = p.reverse_tf != now.reverse_tf;
  std::string error;
  guarded("reconfigure", [&] {
    try {
      NodeConfig next = validateParameters(p);
      if (engine_changes) error = engine_->reconfigure(engineConfig(next));
      if (error.empty()) {
        config_ = std::move(next);
        rebuildEncoder();
      }
    } catch (const std::invalid_argument& e) {
      error = e.what();
    }
    if (!error.empty()) return;
    // Switching publish_tf off and on says "look again": the stop is lifted, and the watch,
    // subscribed anew, gets the latched /tf_static parents still published (which stop tf
    // again). reverse_tf changes our child frame, so the old conflict is not ours any more.
    if (tf_toggled || child_changed) {
      if (p.publish_tf) {
        resumeTf(tf_toggled ? "publish_tf switched off and on"
                            : "reverse_tf changed our child frame");
      }
      tf_watch_sub_.shutdown();
      tf_static_watch_sub_.shutdown();
      watchTf();
    }
    if (engine_changes) writeResolved();
  });
  if (!error.empty()) {
    // The text quotes the value asked for (the integrator name is any string a client sends).
    ROS_WARN("reconfigure refused: %s; keeping the values in force",
             logText(error, 4 * kLogTextBytes).c_str());
  } else if (engine_changes) {
    ROS_INFO(
        "reconfigured: integrator %s, max_dt %g s, torque_timeout %g s, "
        "angular_velocity_stddev %g rad/s (the propagator goes on from the current state)",
        integratorName(engine_->integrator()).c_str(), config_.parameters.max_dt,
        config_.parameters.torque_timeout, config_.parameters.angular_velocity_stddev);
  }
  const Parameters& in_force = config_.parameters;
  live.angular_velocity_stddev = in_force.angular_velocity_stddev;
  live.max_dt = in_force.max_dt;
  live.torque_timeout = in_force.torque_timeout;
  live.publish_tf = in_force.publish_tf;
  live.reverse_tf = in_force.reverse_tf;
  live.integrator = in_force.integrator;
}

std::optional<double> AttitudePropagatorRos::inputLagBeyondWarning() const {
  for (Source source : {Source::Imu, Source::Twist, Source::Torque}) {
    const std::optional<double> lag = engine_->inputLag(source);
    if (lag && std::abs(*lag) > kInputLagWarning) return lag;
  }
  return std::nullopt;
}

void AttitudePropagatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const EngineCounters& c = engine_->counters();
  const ros::WallTime now = ros::WallTime::now();
  const double dt = (now - last_diagnosis_).toSec();
  const double input_rate = dt > 0.0 ? (c.accepted - accepted_at_last_diagnosis_) / dt : 0.0;
  last_diagnosis_ = now;
  accepted_at_last_diagnosis_ = c.accepted;

  const bool expects_input = config_.rate_input != RateInput::None;
  const double silence = last_input_.isZero() ? -1.0 : (now - last_input_).toSec();
  if (expects_input && (silence < 0.0 || silence > 1.0)) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no rate input in the last second");
  } else if (!input_window_problem_.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, input_window_problem_);
  } else if (const std::string fixes = fixes_->warning(c); !fixes.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, fixes);
  } else if (const std::optional<double> lag = inputLagBeyondWarning()) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "inputs arrive %.3f s %s ROS time (sensor clock skewed, or a queue): tf "
                    "lookups at now will miss",
                    std::abs(*lag), *lag > 0.0 ? "behind" : "ahead of");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "propagating");
  }
  const EngineState state = engine_->state();
  status.add("model", engine_->modelName());
  status.add("integrator", integratorName(engine_->integrator()));
  status.add("input_rate_hz", input_rate);
  status.add("received", c.received);
  status.add("accepted", c.accepted);
  status.add("pending", engine_->pending());
  status.add("rejected_non_finite", c.rejected_non_finite);
  status.add("rejected_out_of_range", c.rejected_out_of_range);
  status.add("rejected_no_rate", c.rejected_no_rate);
  status.add("rejected_type", c.rejected_type);
  status.add("rejected_covariance", c.rejected_covariance);
  status.add("dropped_stale", c.dropped_stale);
  status.add("dropped_no_tf", c.dropped_no_tf);
  status.add("dropped_no_time", c.dropped_no_time);
  status.add("late", c.late);
  status.add("gaps", c.gaps);
  status.add("resets", c.resets);
  status.add("jumps_back", c.jumps_back);
  status.add("rejected_future", c.rejected_future);
  status.add("dropped_on_reset", c.dropped_on_reset);
  // Mean ROS time minus stamp on arrival: a constant skew between the sensor's clock and
  // this machine's shows here (WARN above kInputLagWarning).
  for (Source source : {Source::Imu, Source::Twist, Source::Torque}) {
    if (const std::optional<double> lag = engine_->inputLag(source)) {
      status.add(source == Source::Torque ? "torque_lag_s" : "rate_lag_s", *lag);
    }
  }
  status.add("failed_steps", c.failed_steps);
  status.add("pending_overflow", c.pending_overflow);
  status.add("deferred_ticks", c.deferred_ticks);
  status.add("callback_errors", callback_errors_);
  status.add("rejected_bias", c.rejected_bias);
  status.add("tf_conflicts", tf_conflicts_);
  status.add("tf_stopped", tf_stopped_);
  status.add("tf_resumes", tf_resumes_);
  const Eigen::Vector3d& b = engine_->gyroBias();
  status.addf("gyro_bias", "[%g, %g, %g]", b.x(), b.y(), b.z());
  fixes_->diagnose(status, *engine_);
  if (const KinematicPropagator* k = engine_->kinematic()) {
    status.add("rate_samples", config_.parameters.rate_samples);
    status.add("filled_samples", k->filledSamples());
    if (const SensorClockFilter* f = k->stampFilter()) {
      status.add("stamp_filter_period_s", f->period());
      status.add("stamp_filter_offset_s", f->offset());
      status.add("stamp_filter_jitter_s", f->jitter());
      status.add("stamp_filter_rejected", f->rejected());
      status.add("stamp_filter_missed_periods", f->missed());
      status.add("stamp_filter_restarts", f->restarts());
      status.add("stamp_batch", f->batchSize());
      status.add("stamp_filter_unfiltered", f->unfiltered());
    }
  }
  status.add("norm_error", state.norm_error);
  if (engine_->dynamicModel()) {
    status.add("kinetic_energy", state.kinetic_energy);
    status.add("energy_drift", engine_->energyDrift());
    status.add("momentum_drift", engine_->momentumDrift());
  }
}

void AttitudePropagatorRos::closeInputWindow() {
  const ros::WallTime now = ros::WallTime::now();
  if (window_start_.isZero()) {
    window_start_ = now;
    window_start_counters_ = engine_->counters();
    return;
  }
  const double seconds = (now - window_start_).toSec();
  if (seconds < kInputWindow) return;
  const EngineCounters& c = engine_->counters();
  const EngineCounters& s = window_start_counters_;
  // Counts of rate samples lost in the window, by cause. Torque counts with them: the
  // counters do not tell the sources apart (a torque topic rarely fails alone).
  struct Loss {
    std::uint64_t count;
    std::string cause;
  };
  const std::uint64_t received = c.received - s.received;
  const double period = received > 0 ? seconds / static_cast<double>(received) : 0.0;
  const double max_dt = config_.parameters.max_dt;
  char gap_cause[160];
  if (max_dt < period) {
    std::snprintf(gap_cause, sizeof(gap_cause), "max_dt %g s is below the input period %g s",
                  max_dt, period);
  } else {
    std::snprintf(gap_cause, sizeof(gap_cause),
                  "gaps longer than max_dt %g s (input period %g s): messages lost on the way "
                  "or stamps far apart",
                  max_dt, period);
  }
  const Loss losses[] = {
      {c.gaps - s.gaps, gap_cause},
      {c.dropped_stale - s.dropped_stale,
       "stamps at or before the previous one (two publishers on one topic, or a source that "
       "loops)"},
      {c.rejected_future - s.rejected_future,
       "stamps more than max_future ahead of ROS time (clocks not synchronised?)"},
      {c.rejected_non_finite - s.rejected_non_finite, "NaN or infinite rates or stamps"},
      {c.rejected_out_of_range - s.rejected_out_of_range, "rates out of the accepted range"},
      {c.rejected_no_rate - s.rejected_no_rate,
       "angular_velocity_covariance[0] == -1 (REP-145: no rate)"},
      {c.rejected_type - s.rejected_type, "a message type the topic does not take"},
      {c.rejected_covariance - s.rejected_covariance, "rate covariances that are not ones"},
      {c.dropped_no_tf - s.dropped_no_tf, "no transform from the rates' frame to the body yet"},
      {c.dropped_no_time - s.dropped_no_time, "unstamped messages before the first /clock"},
  };
  std::uint64_t lost = 0;
  const Loss* worst = &losses[0];
  for (const Loss& loss : losses) {
    lost += loss.count;
    if (loss.count > worst->count) worst = &loss;
  }
  input_window_problem_.clear();
  if (received > 0 && 2 * lost > received) {
    input_window_problem_ = "most rate samples of the last second were lost (" +
                            std::to_string(std::min(lost, received)) + " of " +
                            std::to_string(received) + "): " + worst->cause;
  }
  window_start_ = now;
  window_start_counters_ = c;
}

}  // namespace attitude_propagator
