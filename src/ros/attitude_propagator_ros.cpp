#include "attitude_propagator/ros/attitude_propagator_ros.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tf2_msgs/TFMessage.h>
#include <boost/make_shared.hpp>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/quaternion.h"
#include "attitude_propagator/ros/conversions.h"
#include "attitude_propagator/ros/parameter_loader.h"

namespace attitude_propagator {

namespace {

// DESIGN §6: time going back by more than this (s) is a looped bag or a restarted clock.
constexpr double kBackwardJump = 1.0;
// Inputs are queued, not dropped, through a burst of this many messages (a bag played fast,
// a load generator); outputs likewise for slow subscribers.
constexpr std::uint32_t kQueueSize = 10000;
// Dynamic model: inputs stamped ahead of the propagator wait for the timer; at most this many
// (a stream stamped far in the future must not grow memory without bound).
constexpr std::size_t kMaxPending = 4096;
// Throttle period (s) of warnings about input that keeps coming bad.
constexpr double kWarnPeriod = 5.0;
// How often ROS time is checked for jumps while no input arrives (s).
constexpr double kWatchdogPeriod = 0.1;

template <class M>
bool isType(const topic_tools::ShapeShifter& message) {
  return message.getDataType() == ros::message_traits::datatype<M>() &&
         message.getMD5Sum() == ros::message_traits::md5sum<M>();
}

/// Deserialises a ShapeShifter into an existing message through a reused buffer, so a
/// steady stream allocates nothing here (instantiate() would allocate a message each time).
template <class M>
void decodeInto(const topic_tools::ShapeShifter& message, std::vector<std::uint8_t>& buffer,
                M& out) {
  buffer.resize(message.size());
  ros::serialization::OStream write(buffer.data(), message.size());
  message.write(write);
  ros::serialization::IStream read(buffer.data(), message.size());
  ros::serialization::deserialize(read, out);
}

bool isFinite(const Eigen::Quaterniond& q) { return q.coeffs().allFinite(); }

}  // namespace

AttitudePropagatorRos::AttitudePropagatorRos(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), config_(loadParameters(pnh)), updater_(nh, pnh, pnh.getNamespace()) {
  if (config_.model == Model::Dynamic) {
    dynamic_.emplace(*config_.dynamic);
  } else {
    kinematic_.emplace(config_.kinematic);
  }
  pending_.reserve(kMaxPending);
  const double stddev = config_.parameters.angular_velocity_stddev;
  default_R_ = stddev * stddev * Eigen::Matrix3d::Identity();

  advertise();
  subscribe();
  updater_.setHardwareID("none");
  updater_.add("state", this, &AttitudePropagatorRos::diagnose);
  last_diagnosis_ = ros::WallTime::now();
  watchdog_timer_ = nh_.createWallTimer(ros::WallDuration(kWatchdogPeriod),
                                        &AttitudePropagatorRos::onWatchdog, this);
  if (dynamic_) {
    dynamic_timer_ = nh_.createTimer(ros::Duration(1.0 / config_.parameters.publish_rate),
                                     &AttitudePropagatorRos::onDynamicTimer, this);
  }
  logModel();
}

AttitudePropagatorRos::~AttitudePropagatorRos() = default;

void AttitudePropagatorRos::advertise() {
  // Published as shared pointers so subscribers in the same nodelet manager get them without
  // a copy. The tf publisher is our own (tf2_ros::TransformBroadcaster publishes by value).
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", kQueueSize);
  imu_pub_ = nh_.advertise<sensor_msgs::Imu>("imu/data", kQueueSize);
  state_pub_ = nh_.advertise<AttitudeState>("attitude_state", kQueueSize);
  reset_srv_ = pnh_.advertiseService("reset", &AttitudePropagatorRos::onReset, this);
  set_state_srv_ = pnh_.advertiseService("set_state", &AttitudePropagatorRos::onSetState, this);
}

void AttitudePropagatorRos::subscribe() {
  const auto hints = ros::TransportHints().tcpNoDelay();
  if (config_.rate_input == RateInput::Imu) {
    rate_sub_ =
        nh_.subscribe("imu/data_raw", kQueueSize, &AttitudePropagatorRos::onImu, this, hints);
  } else if (config_.rate_input == RateInput::Twist) {
    rate_sub_ =
        nh_.subscribe("body_twist", kQueueSize, &AttitudePropagatorRos::onTwist, this, hints);
  }
  if (dynamic_ && config_.torque_input) {
    torque_sub_ =
        nh_.subscribe("torque", kQueueSize, &AttitudePropagatorRos::onTorque, this, hints);
  }
}

void AttitudePropagatorRos::logModel() const {
  const auto& p = config_.parameters;
  if (dynamic_) {
    ROS_INFO(
        "attitude_propagator: dynamic model %s (integrator %s, max_step %g s), "
        "publishing %s -> %s at %g Hz; rate input %s, torque input %s",
        dynamic_->modelName().c_str(), integratorName(dynamic_->integrator()).c_str(),
        config_.dynamic->max_step, p.fixed_frame.c_str(), p.body_frame.c_str(), p.publish_rate,
        config_.parameters.rate_input.c_str(), config_.torque_input ? "on" : "off");
  } else {
    ROS_INFO(
        "attitude_propagator: kinematic model (integrator %s), publishing %s -> %s per "
        "%s message",
        integratorName(kinematic_->integrator()).c_str(), p.fixed_frame.c_str(),
        p.body_frame.c_str(), config_.parameters.rate_input.c_str());
  }
}

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

void AttitudePropagatorRos::onImu(const ros::MessageEvent<const sensor_msgs::Imu>& event) {
  checkRosTime();
  ++counters_.received;
  const sensor_msgs::Imu& msg = *event.getConstMessage();
  if (msg.angular_velocity_covariance[0] == -1.0) {
    // REP-145: element 0 at -1 marks "this message carries no angular velocity".
    ++counters_.rejected_no_rate;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "imu/data_raw: angular_velocity_covariance[0] == -1 (no rate, REP-145): "
                      "rejected (%lu so far)",
                      counters_.rejected_no_rate);
    return;
  }
  if (!allFinite(msg.angular_velocity) || !allFinite(msg.angular_velocity_covariance)) {
    ++counters_.rejected_non_finite;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "imu/data_raw: NaN or infinite angular velocity or covariance: rejected "
                      "(%lu so far)",
                      counters_.rejected_non_finite);
    return;
  }
  const Eigen::Quaterniond* q_BI = mountRotation(msg.header.frame_id);
  if (!q_BI) return;
  const Eigen::Vector3d w_B = *q_BI * toEigen(msg.angular_velocity);
  const Eigen::Matrix3d R_I = covarianceFromMsg(msg.angular_velocity_covariance);
  const Eigen::Matrix3d R_B =
      R_I.isZero(0.0) ? default_R_ : rotateCovariance(R_I, q_BI->toRotationMatrix());
  handleRate(stampOr(msg.header.stamp, event.getReceiptTime()), w_B, R_B, event.getConstMessage(),
             *q_BI);
}

// Twist/TwistStamped and Wrench/WrenchStamped arrive on one topic each, told apart at run
// time; both carry one vector of interest. Decodes into the reused message of its type,
// rejects (and counts) other types and non-finite vectors.
template <class Stamped, class Plain, class Inner, class Field>
bool AttitudePropagatorRos::decodeVectorInput(const topic_tools::ShapeShifter& msg,
                                              const char* topic, const char* what, Stamped& stamped,
                                              Plain& plain, Inner inner, Field field,
                                              VectorInput& out) {
  if (isType<Stamped>(msg)) {
    decodeInto(msg, decode_buffer_, stamped);
    out = {&field(inner(stamped)), stamped.header.stamp, &stamped.header.frame_id};
  } else if (isType<Plain>(msg)) {
    decodeInto(msg, decode_buffer_, plain);
    out = {&field(plain), ros::Time(), nullptr};
  } else {
    ++counters_.rejected_type;
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: message type %s rejected; accepted: %s %s", topic,
                      msg.getDataType().c_str(), ros::message_traits::datatype<Plain>(),
                      ros::message_traits::datatype<Stamped>());
    return false;
  }
  if (!allFinite(*out.value)) {
    ++counters_.rejected_non_finite;
    ROS_WARN_THROTTLE(kWarnPeriod, "%s: NaN or infinite %s: rejected (%lu so far)", topic, what,
                      counters_.rejected_non_finite);
    return false;
  }
  return true;
}

void AttitudePropagatorRos::onTwist(
    const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  checkRosTime();
  ++counters_.received;
  VectorInput in;
  if (!decodeVectorInput<geometry_msgs::TwistStamped, geometry_msgs::Twist>(
          *event.getConstMessage(), "body_twist", "angular rate", twist_stamped_, twist_,
          [](geometry_msgs::TwistStamped& m) -> geometry_msgs::Twist& { return m.twist; },
          [](geometry_msgs::Twist& m) -> geometry_msgs::Vector3& { return m.angular; }, in)) {
    return;
  }
  static const std::string kBody;
  const Eigen::Quaterniond* q_BS = mountRotation(in.frame_id ? *in.frame_id : kBody);
  if (!q_BS) return;
  handleRate(stampOr(in.stamp, event.getReceiptTime()), *q_BS * toEigen(*in.value), default_R_, {},
             *q_BS);
}

void AttitudePropagatorRos::onTorque(
    const ros::MessageEvent<const topic_tools::ShapeShifter>& event) {
  checkRosTime();
  ++counters_.received;
  VectorInput in;
  if (!decodeVectorInput<geometry_msgs::WrenchStamped, geometry_msgs::Wrench>(
          *event.getConstMessage(), "torque", "torque", wrench_stamped_, wrench_,
          [](geometry_msgs::WrenchStamped& m) -> geometry_msgs::Wrench& { return m.wrench; },
          [](geometry_msgs::Wrench& m) -> geometry_msgs::Vector3& { return m.torque; }, in)) {
    return;
  }
  DynamicInput input;
  input.stamp = stampOr(in.stamp, event.getReceiptTime());
  if (!hasTime(input.stamp, "torque")) return;
  input.is_torque = true;
  if (!resolveTorqueFrame(in.frame_id ? *in.frame_id : std::string(), toEigen(*in.value), input)) {
    return;
  }
  last_input_ = ros::WallTime::now();
  submitDynamic(input);
}

bool AttitudePropagatorRos::resolveTorqueFrame(const std::string& frame_id,
                                               const Eigen::Vector3d& tau, DynamicInput& input) {
  const auto& p = config_.parameters;
  input.value = tau;
  input.frame = config_.torque_frame;  // unstamped, or stamped with an empty frame_id
  if (frame_id.empty()) return true;
  if (frame_id == p.body_frame || frame_id == p.fixed_frame) {
    input.frame = frame_id == p.body_frame ? TorqueFrame::Body : TorqueFrame::Fixed;
    return true;
  }
  // A third frame: rotate into the body now; the core takes it as a body torque.
  const auto q_B_frame = torqueFrameRotation(frame_id);
  if (!q_B_frame) return false;
  input.value = *q_B_frame * tau;
  input.frame = TorqueFrame::Body;
  return true;
}

void AttitudePropagatorRos::handleRate(const ros::Time& stamp, const Eigen::Vector3d& w_B,
                                       const Eigen::Matrix3d& R_B,
                                       const sensor_msgs::Imu::ConstPtr& imu,
                                       const Eigen::Quaterniond& q_B_sensor) {
  if (!hasTime(stamp, imu ? "imu/data_raw" : "body_twist")) return;
  last_input_ = ros::WallTime::now();
  if (kinematic_) {
    handleKinematicRate(stamp, w_B, R_B, imu.get(), q_B_sensor);
    return;
  }
  DynamicInput input;
  input.stamp = stamp;
  input.value = w_B;
  input.imu = imu;
  input.q_B_sensor = q_B_sensor;
  submitDynamic(input);
}

void AttitudePropagatorRos::handleKinematicRate(const ros::Time& stamp, const Eigen::Vector3d& w_B,
                                                const Eigen::Matrix3d& R_B,
                                                const sensor_msgs::Imu* imu,
                                                const Eigen::Quaterniond& q_B_sensor) {
  // time() is only defined once anchored (the window is empty before).
  const double t_before = kinematic_->anchored() ? kinematic_->time() : 0.0;
  const Eigen::Quaterniond q_before = kinematic_->orientation();
  const double t = coreTime(stamp);
  const StampOutcome outcome = kinematic_->addSample(t, w_B);
  if (!handleOutcome(outcome, imu ? "imu/data_raw" : "body_twist", stamp.toSec())) return;
  if (outcome == StampOutcome::Advanced) {
    // The step's own rotation drives the covariance, whatever the integrator did inside it.
    const double h = t - t_before;
    const Eigen::Vector3d w_step = logMap(q_before.conjugate() * kinematic_->orientation()) / h;
    P_B_ = propagateOrientationCovariance(P_B_, h, w_step, R_B);
  } else if (outcome != StampOutcome::HeldGap) {
    P_B_.setZero();  // a new anchor: the state there is the given one
  }
  publishState(stamp);
  if (imu) publishImu(*imu, stamp, q_B_sensor);
}

void AttitudePropagatorRos::submitDynamic(const DynamicInput& input) {
  const double t = coreTime(input.stamp);
  if (!dynamic_->anchored() || t <= dynamic_->time()) {
    applyDynamic(input);  // anchors, or late (the core places it), or a jump back
    return;
  }
  // Ahead of the propagator: held until the timer reaches its stamp, so the state published
  // at a grid stamp sees exactly the inputs stamped up to it, and the timer is never left
  // behind a propagator that inputs pushed past the grid.
  if (pending_.size() >= kMaxPending) {
    applyDynamic(pending_.front());
    pending_.erase(pending_.begin());
  }
  const auto at = std::upper_bound(
      pending_.begin(), pending_.end(), input.stamp,
      [](const ros::Time& stamp, const DynamicInput& other) { return stamp < other.stamp; });
  pending_.insert(at, input);
}

void AttitudePropagatorRos::applyDynamic(const DynamicInput& input) {
  const double t = coreTime(input.stamp);
  // The core places an input that arrives after the timer passed its stamp (transport
  // latency) at the last grid point, and drops one not newer than the stream's previous one.
  const bool late = dynamic_->anchored() && t < dynamic_->time();
  const StampOutcome outcome = input.is_torque ? dynamic_->setTorque(t, input.value, input.frame)
                                               : dynamic_->setRate(t, input.value);
  if (late && outcome == StampOutcome::Advanced) ++counters_.late;
  const char* name = input.is_torque ? "torque" : input.imu ? "imu/data_raw" : "body_twist";
  if (handleOutcome(outcome, name, input.stamp.toSec()) && input.imu) {
    publishImu(*input.imu, input.stamp, input.q_B_sensor);
  }
}

void AttitudePropagatorRos::applyPendingUpTo(const ros::Time& stamp) {
  std::size_t n = 0;
  while (n < pending_.size() && pending_[n].stamp <= stamp) ++n;
  for (std::size_t i = 0; i < n && i < pending_.size(); ++i) applyDynamic(pending_[i]);
  pending_.erase(pending_.begin(), pending_.begin() + std::min(n, pending_.size()));
}

const Eigen::Quaterniond* AttitudePropagatorRos::mountRotation(const std::string& frame_id) {
  static const Eigen::Quaterniond kIdentity = Eigen::Quaterniond::Identity();
  if (frame_id.empty() || frame_id == config_.parameters.body_frame) return &kIdentity;
  if (mount_known_ && frame_id == mount_frame_) return &q_B_mount_;
  ensureTfListener();
  const std::string& body = config_.parameters.body_frame;
  std::string error;
  if (!tf_buffer_->canTransform(body, frame_id, ros::Time(0), &error)) {
    ++counters_.dropped_no_tf;
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "rates in frame '%s': waiting for the static transform %s -> %s; "
                      "dropped %lu messages so far (%s)",
                      frame_id.c_str(), body.c_str(), frame_id.c_str(), counters_.dropped_no_tf,
                      error.c_str());
    return nullptr;
  }
  q_B_mount_ = rotationOf(tf_buffer_->lookupTransform(body, frame_id, ros::Time(0))).normalized();
  mount_frame_ = frame_id;
  mount_known_ = true;
  ROS_INFO("rates in frame '%s' are rotated into '%s' by q = [%g, %g, %g, %g] (x y z w)",
           frame_id.c_str(), body.c_str(), q_B_mount_.x(), q_B_mount_.y(), q_B_mount_.z(),
           q_B_mount_.w());
  if (!config_.torque_input) {
    // Cached for good: stop listening, or the listener would keep digesting our own /tf.
    tf_listener_.reset();
    tf_buffer_.reset();
  }
  return &q_B_mount_;
}

std::optional<Eigen::Quaterniond> AttitudePropagatorRos::torqueFrameRotation(
    const std::string& frame_id) {
  ensureTfListener();
  const std::string& body = config_.parameters.body_frame;
  try {
    return rotationOf(tf_buffer_->lookupTransform(body, frame_id, ros::Time(0))).normalized();
  } catch (const tf2::TransformException& e) {
    ++counters_.dropped_no_tf;
    ROS_WARN_THROTTLE(kWarnPeriod, "torque in frame '%s': no transform to '%s' yet: dropped (%s)",
                      frame_id.c_str(), body.c_str(), e.what());
    return std::nullopt;
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

double AttitudePropagatorRos::coreTime(const ros::Time& stamp) {
  if (origin_.isZero()) origin_ = ros::Time(stamp.sec, 0);  // whole seconds keep the grid exact
  return (stamp - origin_).toSec();
}

bool AttitudePropagatorRos::hasTime(const ros::Time& stamp, const char* input) {
  if (!stamp.isZero()) return true;
  // An unstamped message under sim time before the first /clock: no time to put it at.
  ++counters_.dropped_no_time;
  ROS_WARN_THROTTLE(kWarnPeriod, "%s: unstamped message and no ROS time yet (/clock): dropped",
                    input);
  return false;
}

ros::Time AttitudePropagatorRos::stampOr(const ros::Time& stamp, const ros::Time& receipt) {
  return stamp.isZero() ? receipt : stamp;
}

bool AttitudePropagatorRos::handleOutcome(StampOutcome outcome, const char* input, double stamp_s) {
  switch (outcome) {
    case StampOutcome::Anchored:
    case StampOutcome::Advanced:
      ++counters_.accepted;
      return true;
    case StampOutcome::HeldGap:
      ++counters_.accepted;
      ++counters_.gaps;
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: gap longer than max_dt = %g s before stamp %.6f: not integrated "
                        "across, orientation held (%lu gaps so far)",
                        input, config_.parameters.max_dt, stamp_s, counters_.gaps);
      return true;
    case StampOutcome::ResetBackwardJump:
      ++counters_.accepted;
      ++counters_.resets;
      ROS_WARN(
          "%s: stamps jumped back by more than %g s to %.3f (looped bag?): reset to the "
          "initial state",
          input, kBackwardJump, stamp_s);
      P_B_.setZero();
      last_published_ = ros::Time();
      return true;
    case StampOutcome::DroppedStale:
      ++counters_.dropped_stale;
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "%s: stamp %.6f at or before the last one: dropped (%lu so far)", input,
                        stamp_s, counters_.dropped_stale);
      return false;
    case StampOutcome::RejectedNonFinite:
      ++counters_.rejected_non_finite;
      ROS_WARN_THROTTLE(kWarnPeriod, "%s: non-finite value rejected by the propagator (%lu so far)",
                        input, counters_.rejected_non_finite);
      return false;
  }
  return false;
}

void AttitudePropagatorRos::checkRosTime() {
  const ros::Time now = ros::Time::now();
  if (now.isZero()) return;  // sim time before the first /clock
  if (!last_ros_time_.isZero() && (last_ros_time_ - now).toSec() > kBackwardJump) {
    ROS_WARN(
        "ROS time jumped back from %.3f to %.3f s (looped bag or restarted clock): reset "
        "to the initial state",
        last_ros_time_.toSec(), now.toSec());
    ++counters_.resets;
    resetPropagator(true);
    last_ros_time_ = now;
    // Publish the initial state now rather than one timer period later: roscpp restarts
    // its timers a full period after a backward jump.
    if (dynamic_) publishDynamic();
    return;
  }
  last_ros_time_ = now;
}

ros::Time AttitudePropagatorRos::gridStampAtOrBefore(const ros::Time& now) const {
  // long double holds nanoseconds since the epoch exactly (64-bit mantissa on x86), so the
  // grid index does not wobble with rounding.
  const long double rate = config_.parameters.publish_rate;
  const long double k = std::floor(static_cast<long double>(now.toNSec()) * rate / 1e9L);
  const auto ns = static_cast<std::uint64_t>(std::llround(k * 1e9L / rate));
  ros::Time stamp;
  stamp.fromNSec(std::min<std::uint64_t>(ns, now.toNSec()));
  return stamp;
}

void AttitudePropagatorRos::onDynamicTimer(const ros::TimerEvent&) {
  checkRosTime();
  publishDynamic();
}

void AttitudePropagatorRos::publishDynamic() {
  const ros::Time now = ros::Time::now();
  if (now.isZero()) return;
  const ros::Time stamp = gridStampAtOrBefore(now);
  applyPendingUpTo(stamp);
  if (!last_published_.isZero() && stamp <= last_published_) return;
  const double t = coreTime(stamp);
  if (dynamic_->anchored() && t < dynamic_->time()) return;  // set_state pinned a later time
  if (!dynamic_->anchored() || t > dynamic_->time()) {
    const StampOutcome outcome = dynamic_->advanceTo(t);
    if (outcome == StampOutcome::HeldGap) {
      ++counters_.gaps;
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "ROS time advanced by more than max_dt = %g s to %.3f: not integrated "
                        "across, state held",
                        config_.parameters.max_dt, stamp.toSec());
    } else if (outcome == StampOutcome::ResetBackwardJump) {
      ++counters_.resets;
      ROS_WARN("ROS time went back to %.3f s: reset to the initial state", stamp.toSec());
      last_published_ = ros::Time();
    } else if (!stateHoldsAtStamp(outcome)) {
      return;
    }
  }
  publishState(stamp);  // also when an input stamped exactly here brought the state to it
}

void AttitudePropagatorRos::onWatchdog(const ros::WallTimerEvent&) {
  checkRosTime();
  if ((ros::WallTime::now() - last_diagnosis_).toSec() >= updater_.getPeriod()) {
    updater_.force_update();
  }
}

void AttitudePropagatorRos::resetPropagator(bool forget_time) {
  if (kinematic_) kinematic_->reset();
  if (dynamic_) dynamic_->reset();
  pending_.clear();
  P_B_.setZero();
  if (forget_time) {
    origin_ = last_published_ = ros::Time();
  }
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

Eigen::Quaterniond AttitudePropagatorRos::orientation() const {
  return kinematic_ ? kinematic_->orientation() : dynamic_->state().q_WB;
}

Eigen::Vector3d AttitudePropagatorRos::rate() const {
  return kinematic_ ? kinematic_->rate() : dynamic_->state().w_B;
}

bool AttitudePropagatorRos::publishState(const ros::Time& stamp) {
  if (!last_published_.isZero() && stamp <= last_published_) return false;  // one per stamp
  const Eigen::Quaterniond q_WB = orientation();
  const Eigen::Vector3d w_B = rate();
  if (!isFinite(q_WB) || !w_B.allFinite()) {
    // The core guarantees finite states; if that ever breaks, never hand NaN to tf.
    ROS_ERROR_THROTTLE(kWarnPeriod, "propagated state is not finite: reset to the initial state");
    ++counters_.resets;
    resetPropagator(false);
    return false;
  }
  last_published_ = stamp;
  if (config_.parameters.publish_tf) publishTf(stamp, q_WB);
  if (state_pub_.getNumSubscribers() == 0) return true;

  const auto& p = config_.parameters;
  auto msg = boost::make_shared<AttitudeState>();
  msg->header.stamp = stamp;
  msg->header.frame_id = p.fixed_frame;
  msg->child_frame_id = p.body_frame;
  toMsg(q_WB, msg->orientation);
  covarianceToMsg(P_B_, msg->orientation_covariance);
  toMsg(w_B, msg->angular_velocity);
  if (kinematic_) {
    msg->norm_error = kinematic_->normError();
    msg->model = "kinematic";
    msg->integrator = integratorName(kinematic_->integrator());
    msg->steps = kinematic_->steps();
  } else {
    toMsg(dynamic_->angularMomentum_B(), msg->angular_momentum);
    msg->kinetic_energy = dynamic_->kineticEnergy();
    msg->norm_error = dynamic_->normError();
    msg->model = dynamic_->modelName();
    msg->integrator = integratorName(dynamic_->integrator());
    msg->steps = dynamic_->steps();
  }
  state_pub_.publish(msg);
  return true;
}

void AttitudePropagatorRos::publishTf(const ros::Time& stamp, const Eigen::Quaterniond& q_WB) {
  const auto& p = config_.parameters;
  auto msg = boost::make_shared<tf2_msgs::TFMessage>();
  msg->transforms.resize(1);
  geometry_msgs::TransformStamped& t = msg->transforms[0];
  t.header.stamp = stamp;
  if (p.reverse_tf) {
    t.header.frame_id = p.body_frame;
    t.child_frame_id = p.fixed_frame;
    toMsg(q_WB.conjugate(), t.transform.rotation);
  } else {
    t.header.frame_id = p.fixed_frame;
    t.child_frame_id = p.body_frame;
    toMsg(q_WB, t.transform.rotation);
  }
  tf_pub_.publish(msg);
}

void AttitudePropagatorRos::publishImu(const sensor_msgs::Imu& input, const ros::Time& stamp,
                                       const Eigen::Quaterniond& q_BI) {
  if (imu_pub_.getNumSubscribers() == 0) return;
  auto msg = boost::make_shared<sensor_msgs::Imu>(input);
  msg->header.stamp = stamp;
  // REP-145: the orientation of the IMU's own frame; its error covariance in that frame.
  toMsg(orientation() * q_BI, msg->orientation);
  const Eigen::Matrix3d C_IB = q_BI.conjugate().toRotationMatrix();
  covarianceToMsg(rotateCovariance(P_B_, C_IB), msg->orientation_covariance);
  imu_pub_.publish(msg);
}

// ---------------------------------------------------------------------------------------------
// Services and diagnostics
// ---------------------------------------------------------------------------------------------

bool AttitudePropagatorRos::onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  ++counters_.resets;
  resetPropagator(false);
  ROS_INFO("reset to the initial state; the next input anchors time");
  return true;
}

bool AttitudePropagatorRos::onSetState(SetState::Request& request, SetState::Response& response) {
  checkRosTime();
  const ros::Time stamp = stampOr(request.header.stamp, ros::Time::now());
  if (stamp.isZero()) {
    response.success = false;
    response.message = "no ROS time yet (use_sim_time without /clock): give header.stamp";
    return true;
  }
  Eigen::Quaterniond q_WB = toEigen(request.orientation);
  const Eigen::Vector3d w_B = toEigen(request.angular_velocity);
  if (isFinite(q_WB) && q_WB.norm() > 0.0) q_WB.normalize();
  try {
    const double t = coreTime(stamp);
    if (kinematic_) {
      kinematic_->setState(t, q_WB, w_B);
    } else {
      dynamic_->setState(t, DynamicState{q_WB, w_B});
    }
  } catch (const std::invalid_argument& e) {
    response.success = false;
    response.message = e.what();
    return true;
  }
  P_B_.setZero();
  publishState(stamp);
  response.success = true;
  response.message = "state set at " + std::to_string(stamp.toSec()) + " s";
  return true;
}

void AttitudePropagatorRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const ros::WallTime now = ros::WallTime::now();
  const double dt = (now - last_diagnosis_).toSec();
  const double input_rate =
      dt > 0.0 ? (counters_.accepted - accepted_at_last_diagnosis_) / dt : 0.0;
  last_diagnosis_ = now;
  accepted_at_last_diagnosis_ = counters_.accepted;

  const bool expects_input = config_.rate_input != RateInput::None;
  const double silence = last_input_.isZero() ? -1.0 : (now - last_input_).toSec();
  if (expects_input && (silence < 0.0 || silence > 1.0)) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no rate input in the last second");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "propagating");
  }
  status.add("model", dynamic_ ? dynamic_->modelName() : std::string("kinematic"));
  status.add("integrator",
             integratorName(dynamic_ ? dynamic_->integrator() : kinematic_->integrator()));
  status.add("input_rate_hz", input_rate);
  status.add("received", counters_.received);
  status.add("accepted", counters_.accepted);
  status.add("pending", pending_.size());
  status.add("rejected_non_finite", counters_.rejected_non_finite);
  status.add("rejected_no_rate", counters_.rejected_no_rate);
  status.add("rejected_type", counters_.rejected_type);
  status.add("dropped_stale", counters_.dropped_stale);
  status.add("dropped_no_tf", counters_.dropped_no_tf);
  status.add("dropped_no_time", counters_.dropped_no_time);
  status.add("late", counters_.late);
  status.add("gaps", counters_.gaps);
  status.add("resets", counters_.resets);
  status.add("norm_error", kinematic_ ? kinematic_->normError() : dynamic_->normError());
  if (dynamic_) {
    status.add("kinetic_energy", dynamic_->kineticEnergy());
    status.add("energy_drift", dynamic_->energyDrift());
    status.add("momentum_drift", dynamic_->momentumDrift());
    status.add("failed_steps", dynamic_->failedSteps());
  }
}

}  // namespace attitude_propagator
