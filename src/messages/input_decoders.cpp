#include "attitude_propagator/messages/input_decoders.h"

#include <algorithm>
#include <utility>

#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/imu_input.h"
#include "attitude_propagator/messages/input_roles.h"
#include "attitude_propagator/messages/refusal_table.h"

namespace attitude_propagator {

const char* inputTopicName(Source source) { return inputRoleOf(source).topic; }

const char* refusedCounter(Refused why) {
  const RefusalRow& row = refusalRow(why);
  return row.input_counter ? row.input_counter : row.fix_counter;
}

void countRefusal(AttitudeEngine& engine, Refused why) {
  const RefusalRow& row = refusalRow(why);
  if (row.rejection) engine.reject(*row.rejection);
  if (row.bias) engine.rejectBias();
  // A fix's refusal only: FixDecoder counts it (fix_decoder.h).
}

DecoderFrames DecoderFrames::of(const NodeConfig& config) {
  return {config.parameters.body_frame, config.parameters.fixed_frame, config.torque_frame};
}

std::optional<Stamp> stampOf(const ros::Time& header, const ros::Time& arrival) {
  const ros::Time time = header.isZero() ? arrival : header;
  if (time.isZero()) return std::nullopt;
  return toStamp(time);
}

namespace {

Refusal refusal(Refused why) {
  Refusal r;
  r.why = why;
  return r;
}

Decoded<Reading> reading(Source source, const ros::Time& header, const ros::Time& arrival,
                         const geometry_msgs::Vector3& value, const std::string& frame_id) {
  const auto stamp = stampOf(header, arrival);
  if (!stamp) return {std::nullopt, refusal(Refused::NoTime)};
  Reading r;
  r.source = source;
  r.stamp = *stamp;
  r.value = toEigen(value);
  r.frame_id = frame_id;
  return {std::move(r), std::nullopt};
}

const std::string kNoFrame;

// A reading taken into the body by q_BS (identity when `in_body`). A covariance of zeros (none
// given) or a non-finite one goes on as it is: the engine takes its default or rejects it.
BodyVector intoBody(const Reading& r, const Eigen::Quaterniond& q_BS, bool in_body) {
  BodyVector out;
  out.stamp = r.stamp;
  out.value_B = q_BS * r.value;
  const Eigen::Matrix3d& R_S = r.covariance;
  out.covariance_B = in_body || R_S.isZero(0.0) || !R_S.allFinite()
                         ? R_S
                         : rotateCovariance(R_S, q_BS.toRotationMatrix());
  return out;
}

// A frame tf has no transform to the body for, with tf's error.
Refusal noTransform(const std::string& frame, std::string error) {
  Refusal r = refusal(Refused::NoTransform);
  r.frame = frame;
  r.detail = std::move(error);
  return r;
}

// A frame id refused by the frame id rule (frame_ids.h), as `why`.
Refusal badFrame(Refused why, const std::string& frame) {
  Refusal r = refusal(why);
  r.frame = frame;
  r.detail = kFrameIdRule;
  return r;
}

}  // namespace

Decoded<Reading> readImu(const sensor_msgs::Imu& msg, const ros::Time& arrival) {
  if (const auto refused = refuseImuRate(msg)) {
    Refusal r =
        refusal(refused->why == Rejection::NoRate ? Refused::NoRate : Refused::BadCovariance);
    r.check = refused->check;
    return {std::nullopt, r};
  }
  auto read =
      reading(Source::Imu, msg.header.stamp, arrival, msg.angular_velocity, msg.header.frame_id);
  if (read) read.value->covariance = covarianceFromMsg(msg.angular_velocity_covariance);
  return read;
}

std::optional<Reading> readImuAcceleration(const sensor_msgs::Imu& msg, const ros::Time& arrival) {
  // REP-145: linear_acceleration_covariance[0] == -1 says the message carries no acceleration.
  if (msg.linear_acceleration_covariance[0] == -1.0) return std::nullopt;
  auto read =
      reading(Source::Imu, msg.header.stamp, arrival, msg.linear_acceleration, msg.header.frame_id);
  if (!read) return std::nullopt;
  read.value->covariance = covarianceFromMsg(msg.linear_acceleration_covariance);
  return read.value;
}

Decoded<Reading> readMagneticField(const sensor_msgs::MagneticField& msg,
                                   const ros::Time& arrival) {
  auto read =
      reading(Source::Imu, msg.header.stamp, arrival, msg.magnetic_field, msg.header.frame_id);
  if (read) read.value->covariance = covarianceFromMsg(msg.magnetic_field_covariance);
  return read;
}

Decoded<Reading> readTwist(const geometry_msgs::Twist& msg, const ros::Time& arrival) {
  return reading(Source::Twist, ros::Time(), arrival, msg.angular, kNoFrame);
}

Decoded<Reading> readTwist(const geometry_msgs::TwistStamped& msg, const ros::Time& arrival) {
  return reading(Source::Twist, msg.header.stamp, arrival, msg.twist.angular, msg.header.frame_id);
}

Decoded<Reading> readWrench(const geometry_msgs::Wrench& msg, const ros::Time& arrival) {
  return reading(Source::Torque, ros::Time(), arrival, msg.torque, kNoFrame);
}

Decoded<Reading> readWrench(const geometry_msgs::WrenchStamped& msg, const ros::Time& arrival) {
  return reading(Source::Torque, msg.header.stamp, arrival, msg.wrench.torque, msg.header.frame_id);
}

TopicType::TopicType(std::vector<std::pair<std::string, std::string>> types)
    : types_(std::move(types)) {}

std::optional<Refusal> TopicType::admit(const std::string& datatype, const std::string& md5) {
  const bool known = std::any_of(types_.begin(), types_.end(), [&](const auto& type) {
    return datatype == type.first && md5 == type.second;
  });
  if (known && datatype_.empty()) datatype_ = datatype;
  if (known && datatype == datatype_) return std::nullopt;
  Refusal r = refusal(Refused::WrongType);
  r.detail = datatype;
  return r;
}

std::optional<std::string> TopicType::otherRegistered(const std::string& registered) const {
  if (datatype_.empty() || registered.empty() || registered == "*" || registered == datatype_) {
    return std::nullopt;
  }
  return registered;
}

std::string TopicType::accepted() const {
  std::string out;
  for (std::size_t i = 0; i < types_.size(); ++i) {
    if (i > 0) out += i + 1 == types_.size() ? " or " : ", ";
    out += types_[i].first;
  }
  return out;
}

InputDecoders::InputDecoders(DecoderFrames frames)
    : frames_(std::move(frames)),
      twist_type_(TopicType::accepting(inputRoleOf(Source::Twist).types)),
      torque_type_(TopicType::accepting(inputRoleOf(Source::Torque).types)) {}

DecodedInput InputDecoders::refuse(Refusal refusal) {
  DecodedInput out;
  out.refusal = std::move(refusal);
  return out;
}

DecodedInput InputDecoders::imu(const sensor_msgs::Imu& msg, const ros::Time& arrival,
                                FrameSource* frames) {
  DecodedInput out = rate(readImu(msg, arrival), frames);
  if (out) out.acceleration = acceleration(readImuAcceleration(msg, arrival), out);
  return out;
}

std::optional<BodyVector> InputDecoders::acceleration(const std::optional<Reading>& f_S,
                                                      const DecodedInput& rate) {
  if (!f_S) return std::nullopt;
  // The rate's frame, so the rate's mount (the identity for the body's own frame).
  const bool in_body = rate.q_BS.coeffs() == Eigen::Quaterniond::Identity().coeffs();
  return intoBody(*f_S, rate.q_BS, in_body);
}

DecodedField InputDecoders::magneticField(const sensor_msgs::MagneticField& msg,
                                          const ros::Time& arrival, FrameSource* frames) {
  DecodedField out;
  const Decoded<Reading> read = readMagneticField(msg, arrival);
  if (!read) {
    out.refusal = read.refusal;
    return out;
  }
  const auto frame_id = frame_ids_.admit(read->frame_id);
  if (!frame_id) {
    out.refusal = badFrame(Refused::NoTransform, read->frame_id);
    return out;
  }
  const std::string& frame = *frame_id;
  const bool in_body = frame.empty() || frame == frames_.body;
  if (!in_body && frame != mount_frame_ && frame != mag_frame_) {
    // A magnetometer on a frame of its own: its mount looked up once, as the rates' is.
    std::string error = "no frame source";
    const auto q =
        frames ? frames->rotation(frames_.body, frame, ros::Time(), &error) : std::nullopt;
    if (!q) {
      out.refusal = noTransform(frame, std::move(error));
      return out;
    }
    mag_frame_ = frame;
    q_BM_ = *q;
    out.new_mount = true;
  }
  const Eigen::Quaterniond q_BM = in_body                 ? Eigen::Quaterniond::Identity()
                                  : frame == mount_frame_ ? q_BS_
                                                          : q_BM_;
  mag_settled_ = true;
  out.value = intoBody(*read, q_BM, in_body);
  return out;
}

DecodedInput InputDecoders::twist(const geometry_msgs::Twist& msg, const ros::Time& arrival) {
  return rate(readTwist(msg, arrival), nullptr);
}

DecodedInput InputDecoders::twist(const geometry_msgs::TwistStamped& msg, const ros::Time& arrival,
                                  FrameSource* frames) {
  return rate(readTwist(msg, arrival), frames);
}

DecodedInput InputDecoders::torque(const geometry_msgs::Wrench& msg, const ros::Time& arrival) {
  return torque(readWrench(msg, arrival), nullptr);
}

DecodedInput InputDecoders::torque(const geometry_msgs::WrenchStamped& msg,
                                   const ros::Time& arrival, FrameSource* frames) {
  return torque(readWrench(msg, arrival), frames);
}

DecodedInput InputDecoders::rate(const Decoded<Reading>& read, FrameSource* frames) {
  if (!read) return refuse(*read.refusal);
  const Reading& r = *read;
  const auto frame_id = frame_ids_.admit(r.frame_id);
  if (!frame_id) return refuse(badFrame(Refused::NoTransform, r.frame_id));
  DecodedInput out;
  const std::string& frame = *frame_id;
  if (!frame.empty() && frame != frames_.body && frame != mount_frame_) {
    // A frame not seen before (or another one than the mount's): the mount looked up once.
    std::string error = "no frame source";
    const auto q =
        frames ? frames->rotation(frames_.body, frame, ros::Time(), &error) : std::nullopt;
    if (!q) {
      Refusal refused = refusal(Refused::NoTransform);
      refused.frame = frame;
      refused.detail = error;
      return refuse(std::move(refused));
    }
    mount_frame_ = frame;
    q_BS_ = *q;
    out.new_mount = true;
  }
  const bool in_body = frame.empty() || frame == frames_.body;
  out.q_BS = in_body ? Eigen::Quaterniond::Identity() : q_BS_;
  Input input;
  input.source = r.source;
  input.stamp = r.stamp;
  input.value = out.q_BS * r.value;
  const Eigen::Matrix3d& R_S = r.covariance;
  input.rate_covariance_B = in_body || R_S.isZero(0.0) || !R_S.allFinite()
                                ? R_S
                                : rotateCovariance(R_S, out.q_BS.toRotationMatrix());
  out.value = std::move(input);
  return out;
}

DecodedInput InputDecoders::torque(const Decoded<Reading>& read, FrameSource* frames) {
  if (!read) return refuse(*read.refusal);
  const Reading& r = *read;
  Input input;
  input.source = Source::Torque;
  input.stamp = r.stamp;
  input.value = r.value;
  input.frame = frames_.torque_frame;  // unstamped, or stamped with an empty frame_id
  const auto frame_id = frame_ids_.admit(r.frame_id);
  if (!frame_id) return refuse(badFrame(Refused::NoTransform, r.frame_id));
  const std::string& frame = *frame_id;
  if (frame == frames_.body && !frame.empty()) {
    input.frame = TorqueFrame::Body;
  } else if (frame == frames_.fixed && !frame.empty()) {
    input.frame = TorqueFrame::Fixed;
  } else if (!frame.empty() && r.value.allFinite()) {
    // A third frame: rotated into the body now (the latest transform: a torque sensor may
    // move); the core takes it as a body torque. A non-finite torque needs no lookup: the
    // engine rejects and counts it.
    std::string error = "no frame source";
    const auto q_BF =
        frames ? frames->rotation(frames_.body, frame, ros::Time(), &error) : std::nullopt;
    if (!q_BF) {
      Refusal refused = refusal(Refused::NoTransform);
      refused.frame = frame;
      refused.detail = error;
      return refuse(std::move(refused));
    }
    input.value = *q_BF * r.value;
    input.frame = TorqueFrame::Body;
  }
  DecodedInput out;
  out.value = std::move(input);
  return out;
}

Decoded<BiasSample> InputDecoders::bias(const geometry_msgs::Vector3Stamped& msg,
                                        const ros::Time& now) {
  const auto frame_id = frame_ids_.admit(msg.header.frame_id);
  if (!frame_id) return {std::nullopt, badFrame(Refused::BiasFrame, msg.header.frame_id)};
  const std::string& frame = *frame_id;
  const bool in_body = frame.empty() || frame == frames_.body;
  const bool in_mount = !mount_frame_.empty() && frame == mount_frame_;
  if (!in_body && !in_mount) {
    Refusal refused = refusal(Refused::BiasFrame);
    refused.frame = frame;
    return {std::nullopt, std::move(refused)};
  }
  BiasSample b;
  const Eigen::Vector3d value = toEigen(msg.vector);
  b.b_B = in_mount ? Eigen::Vector3d(q_BS_ * value) : value;
  // Unstamped: from `now` on (zero: from the start).
  b.stamp = toStamp(msg.header.stamp.isZero() ? now : msg.header.stamp);
  return {b, std::nullopt};
}

}  // namespace attitude_propagator
