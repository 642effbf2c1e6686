// The decoders of every input message, shared by the node and the bag tools so both take and
// refuse alike: sensor_msgs/Imu, geometry_msgs/Twist and TwistStamped (body_twist), Wrench and
// WrenchStamped (torque), and the gyro bias (Vector3Stamped). Each turns a message, the time it
// arrived (receipt time in the node, record time in a bag) and a FrameSource into an engine
// Input, or into a named Refusal that the caller counts once (countRefusal) and reports.
//
// The rules (docs/design.md §5.4, §7.5):
// - stamps: a zero header stamp (or no header) means the arrival time; none at all (sim time
//   before the first /clock): refused, NoTime;
// - rates (Imu, Twist): frame empty or body_frame: as they are; another frame S: rotated by the
//   mount q_BS = lookupTransform(body_frame, S, latest), looked up once and kept until the rates
//   come in yet another frame; an IMU's covariance becomes C_BS R_S C_BSᵀ; unknown: NoTransform;
// - torque (Wrench, WrenchStamped): body_frame: a body torque; fixed_frame: a fixed-frame
//   torque; empty or unstamped: the torque_frame parameter; a third frame F: rotated into the
//   body through the latest transform (looked up per message: a torque sensor may move) and
//   then a body torque; unknown: NoTransform. A non-finite torque is passed to the engine
//   without a lookup (it rejects and counts it);
// - gyro bias: frame empty or body_frame: as it is; the rates' mount frame once known: rotated
//   by q_BS; any other frame: refused, BiasFrame;
// - frame ids (frame_ids.h): a leading '/' is removed (tf1's `/imu` is `imu`), warned once per
//   frame (takeFrameWarnings); a frame id with a space or line break is refused: NoTransform
//   (rates, torques) or BiasFrame, naming the rule in `detail`;
// - accelerometer (Imu, with its rate): REP-145's linear_acceleration_covariance[0] == -1 means
//   none (nothing to submit, not a refusal); otherwise the specific force f_S is taken into the
//   body by the rate's own mount, f_B = q_BS f_S, its covariance C_BS R_S C_BSᵀ (all zero: none
//   given, the engine's accel_stddev), with the rate's stamp; a refused rate's is not taken;
// - magnetic field (MagneticField, imu/mag): the stamp rule, then the rates' frame rule with a
//   mount of its own (the rates' mount when it is the same frame): m_B = q_BM m_M, covariance
//   C_BM R_M C_BMᵀ (all zero: mag_stddev); unknown frame: NoTransform;
// - world_frame changes nothing here: inputs are in REP-103's axes (FLU bodies, docs/
//   conventions.md §2.2); an FRD sensor gives its frame a mount of its own on tf;
// - types: a topic that takes a plain and a stamped type (body_twist, torque) takes the type of
//   its first message of either; a message of another type is refused, WrongType.
#pragma once

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Geometry>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/messages/frame_ids.h"
#include "attitude_propagator/messages/frame_source.h"

namespace attitude_propagator {

/// The topic an input of `source` comes in on, relative to the node's namespace, as the node
/// subscribes it: imu/data_raw, body_twist, torque. For the log and the diagnostics.
const char* inputTopicName(Source source);

/// Why a decoder refused a message. Each goes to one engine counter (refusedCounter), but for
/// NoOrientation, which only fixes meet (FixDecoder counts fixes' refusals: fix_decoder.h).
enum class Refused {
  NoRate,
  BadCovariance,
  WrongType,
  NoTransform,
  NoTime,
  BiasFrame,
  NoOrientation,  ///< an Imu fix without orientation (orientation_covariance[0] == -1)
  FixBodyFrame,   ///< a fix whose header frame is body_frame: it would correct the state by itself
};
/// The counter a refusal is counted in: rejected_no_rate, rejected_covariance, rejected_type,
/// dropped_no_tf, dropped_no_time, rejected_bias; NoOrientation: fixes_refused_no_orientation;
/// FixBodyFrame: fixes_refused_body_frame.
const char* refusedCounter(Refused why);
/// Counts a refusal in the engine's counters, once.
void countRefusal(AttitudeEngine& engine, Refused why);

struct Refusal {
  Refused why = Refused::NoTime;
  RateCovarianceCheck check = RateCovarianceCheck::Ok;  ///< BadCovariance: which test failed
  std::string frame;   ///< NoTransform, BiasFrame: the frame refused
  std::string detail;  ///< NoTransform: tf's error; WrongType: the type received
};

/// A value or the reason there is none.
template <class T>
struct Decoded {
  std::optional<T> value;
  std::optional<Refusal> refusal;  ///< set exactly when value is not
  explicit operator bool() const { return value.has_value(); }
  const T& operator*() const { return *value; }
  const T* operator->() const { return &*value; }
};

/// The frames the rules name.
struct DecoderFrames {
  std::string body;                              ///< body_frame
  std::string fixed;                             ///< fixed_frame
  TorqueFrame torque_frame = TorqueFrame::Body;  ///< torque_frame: unstamped torques
  static DecoderFrames of(const NodeConfig& config);
};

/// A message read, in its own frame, before the frame rules: what the bag tool that estimates
/// the mount itself (evaluate_bag) takes, and what the rules start from.
struct Reading {
  Source source = Source::Imu;
  Stamp stamp = 0;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();       ///< ω_S (rad/s) or τ (N m)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< Imu: R_S; zero: none given
  std::string frame_id;                                  ///< empty: none or unstamped
};

/// A vector measured in the body frame at `stamp`, for the engine's gravity or field
/// measurements (submitAcceleration, submitMagneticField).
struct BodyVector {
  Stamp stamp = 0;
  Eigen::Vector3d value_B = Eigen::Vector3d::Zero();       ///< f_B (m/s^2) or m_B (T)
  Eigen::Matrix3d covariance_B = Eigen::Matrix3d::Zero();  ///< zero: none given
};

/// A rate or torque decoded for the engine.
struct DecodedInput : Decoded<Input> {
  Eigen::Quaterniond q_BS = Eigen::Quaterniond::Identity();  ///< rates: the mount applied
  bool new_mount = false;  ///< rates: q_BS was looked up for this message (a new mount frame)
  /// Imu: the accelerometer's specific force in the body, at the rate's stamp; none when
  /// REP-145 says there is none (linear_acceleration_covariance[0] == -1).
  std::optional<BodyVector> acceleration;
};

/// A magnetic field decoded for the engine, and whether its mount was looked up for it.
struct DecodedField : Decoded<BodyVector> {
  bool new_mount = false;
};

/// A gyro bias in the body frame, in force from `stamp`.
struct BiasSample {
  Stamp stamp = 0;
  Eigen::Vector3d b_B = Eigen::Vector3d::Zero();
};

/// The stamp rule: the header stamp, or `arrival` when it is zero; none when both are zero.
std::optional<Stamp> stampOf(const ros::Time& header, const ros::Time& arrival);

/// An Imu's rate in its own frame, or NoRate (REP-145), BadCovariance, NoTime.
Decoded<Reading> readImu(const sensor_msgs::Imu& msg, const ros::Time& arrival);
/// An Imu's specific force f_S (m/s^2) in its own frame with the stamp rule; none when REP-145
/// says there is none (linear_acceleration_covariance[0] == -1) or there is no time.
std::optional<Reading> readImuAcceleration(const sensor_msgs::Imu& msg, const ros::Time& arrival);
/// A MagneticField's m_S (T) in its own frame, or NoTime.
Decoded<Reading> readMagneticField(const sensor_msgs::MagneticField& msg, const ros::Time& arrival);
Decoded<Reading> readTwist(const geometry_msgs::Twist& msg, const ros::Time& arrival);
Decoded<Reading> readTwist(const geometry_msgs::TwistStamped& msg, const ros::Time& arrival);
Decoded<Reading> readWrench(const geometry_msgs::Wrench& msg, const ros::Time& arrival);
Decoded<Reading> readWrench(const geometry_msgs::WrenchStamped& msg, const ros::Time& arrival);

/// The bytes of a serialised message (topic_tools::ShapeShifter, rosbag::MessageInstance),
/// copied into `buffer` (resized to them).
template <class Serialized>
void serializedBytes(const Serialized& message, std::vector<std::uint8_t>& buffer) {
  const std::uint32_t size = message.size();
  buffer.resize(size);
  ros::serialization::OStream write(buffer.data(), size);
  message.write(write);
}

/// Deserialises a serialised message (topic_tools::ShapeShifter, rosbag::MessageInstance)
/// into an existing one through a reused buffer: a steady stream allocates nothing here.
template <class Serialized, class M>
void deserializeInto(const Serialized& message, std::vector<std::uint8_t>& buffer, M& out) {
  serializedBytes(message, buffer);
  ros::serialization::IStream read(buffer.data(), static_cast<std::uint32_t>(buffer.size()));
  ros::serialization::deserialize(read, out);
}

/// A TFMessage's transform count is checked against the message's size first: deserialising
/// makes room for that many transforms before reading them, and a damaged count (a damaged
/// bag) would ask for up to 2^32 of them. A transform takes at least 76 bytes (header: seq,
/// stamp and an empty frame_id; an empty child_frame_id; translation and rotation). Throws
/// ros::serialization::StreamOverrunException, as a message too short for its fields does.
template <class Serialized>
void deserializeInto(const Serialized& message, std::vector<std::uint8_t>& buffer,
                     tf2_msgs::TFMessage& out) {
  serializedBytes(message, buffer);
  const std::size_t size = buffer.size();
  std::uint32_t count = 0;
  if (size >= 4) std::memcpy(&count, buffer.data(), 4);
  constexpr std::uint64_t kLeastTransformBytes = 4 + 8 + 4 + 4 + 24 + 32;
  if (size < 4 || std::uint64_t(count) * kLeastTransformBytes > size - 4) {
    throw ros::serialization::StreamOverrunException(
        "tf2_msgs/TFMessage: " + std::to_string(count) + " transforms cannot fit in " +
        std::to_string(size) + " bytes");
  }
  ros::serialization::IStream read(buffer.data(), static_cast<std::uint32_t>(size));
  ros::serialization::deserialize(read, out);
}

/// One type per topic that takes several types (a plain and a stamped one; the fix topic's
/// four): the first message of an accepted type fixes it; a message of any other type, or of
/// another accepted one later, is WrongType.
class TopicType {
 public:
  /// Accepts the types of an input topic's row (input_roles.h), in their order.
  static TopicType accepting(const std::vector<std::pair<std::string, std::string>>& types) {
    return TopicType(types);
  }
  /// Nothing when the message's type is the topic's (fixing it at the first), else WrongType
  /// naming the type received.
  std::optional<Refusal> admit(const std::string& datatype, const std::string& md5);
  /// The topic's type; empty before its first message of an accepted type.
  const std::string& datatype() const { return datatype_; }
  /// `registered`, the type the ROS master holds for the topic (its latest publisher's), when
  /// it is not the topic's: another publisher, whose connection ROS 1 refuses, so that its
  /// messages never arrive to be refused. Nothing before the topic's first message, for the
  /// topic's own type, or for "*" (a publisher of any type).
  std::optional<std::string> otherRegistered(const std::string& registered) const;
  template <class M>
  bool is() const {
    return datatype_ == ros::message_traits::datatype<M>();
  }
  bool stamped() const { return types_.size() > 1 && datatype_ == types_[1].first; }
  /// The first two types accepted, for messages.
  const std::string& plainType() const { return types_.front().first; }
  const std::string& stampedType() const { return types_.back().first; }
  /// Every type accepted, "a, b or c".
  std::string accepted() const;

 private:
  explicit TopicType(std::vector<std::pair<std::string, std::string>> types);
  std::vector<std::pair<std::string, std::string>> types_;  // (datatype, md5)
  std::string datatype_;
};

/// Every input of one node (or one bag run): the frames, the rates' mount, each topic's type,
/// and scratch messages reused for serialised input.
class InputDecoders {
 public:
  explicit InputDecoders(DecoderFrames frames);

  /// `frames` is asked only when a rule needs a transform; it may be null (then such a message
  /// is NoTransform).
  DecodedInput imu(const sensor_msgs::Imu& msg, const ros::Time& arrival, FrameSource* frames);
  DecodedInput twist(const geometry_msgs::Twist& msg, const ros::Time& arrival);
  DecodedInput twist(const geometry_msgs::TwistStamped& msg, const ros::Time& arrival,
                     FrameSource* frames);
  DecodedInput torque(const geometry_msgs::Wrench& msg, const ros::Time& arrival);
  DecodedInput torque(const geometry_msgs::WrenchStamped& msg, const ros::Time& arrival,
                      FrameSource* frames);
  /// imu/mag: the field in the body frame (the rates' frame rule, a mount of its own).
  DecodedField magneticField(const sensor_msgs::MagneticField& msg, const ros::Time& arrival,
                             FrameSource* frames);
  /// `now`: the time an unstamped bias takes effect from (ROS time in the node, zero before
  /// the first /clock: from the start; the record time in a bag).
  Decoded<BiasSample> bias(const geometry_msgs::Vector3Stamped& msg, const ros::Time& now);

  /// body_twist and torque as they arrive on a topic of either type (ShapeShifter in the node,
  /// rosbag::MessageInstance in a bag): the type rule, then twist() or torque().
  template <class Serialized>
  DecodedInput twistTopic(const Serialized& m, const ros::Time& arrival, FrameSource* frames) {
    if (auto refused = twist_type_.admit(m.getDataType(), m.getMD5Sum())) return refuse(*refused);
    if (twist_type_.stamped()) {
      deserializeInto(m, buffer_, twist_stamped_);
      return twist(twist_stamped_, arrival, frames);
    }
    deserializeInto(m, buffer_, twist_);
    return twist(twist_, arrival);
  }
  template <class Serialized>
  DecodedInput torqueTopic(const Serialized& m, const ros::Time& arrival, FrameSource* frames) {
    if (auto refused = torque_type_.admit(m.getDataType(), m.getMD5Sum())) return refuse(*refused);
    if (torque_type_.stamped()) {
      deserializeInto(m, buffer_, wrench_stamped_);
      return torque(wrench_stamped_, arrival, frames);
    }
    deserializeInto(m, buffer_, wrench_);
    return torque(wrench_, arrival);
  }
  /// body_twist read in its own frame (the type rule, the stamp rule): evaluate_bag.
  template <class Serialized>
  Decoded<Reading> readTwistTopic(const Serialized& m, const ros::Time& arrival) {
    if (auto refused = twist_type_.admit(m.getDataType(), m.getMD5Sum())) {
      return {std::nullopt, std::move(refused)};
    }
    if (twist_type_.stamped()) {
      deserializeInto(m, buffer_, twist_stamped_);
      return readTwist(twist_stamped_, arrival);
    }
    deserializeInto(m, buffer_, twist_);
    return readTwist(twist_, arrival);
  }

  const DecoderFrames& frames() const { return frames_; }
  const TopicType& twistType() const { return twist_type_; }
  const TopicType& torqueType() const { return torque_type_; }
  /// The rates' mount: its frame (empty until one is looked up) and q_BS.
  const std::string& mountFrame() const { return mount_frame_; }
  const Eigen::Quaterniond& mount() const { return q_BS_; }
  /// The field's mount: its frame (empty until one is looked up, or when it is the rates') and
  /// q_BM; magSettled(): a field has been taken, so its frame needs no further lookup.
  const std::string& magFrame() const { return mag_frame_; }
  const Eigen::Quaterniond& magMount() const { return q_BM_; }
  bool magSettled() const { return mag_settled_; }
  /// The warnings of frame ids with a leading '/' met since the last call (one per frame).
  std::vector<std::string> takeFrameWarnings() { return frame_ids_.takeWarnings(); }

 private:
  static DecodedInput refuse(Refusal refusal);
  /// The rate rule: a reading in its frame to a body rate input.
  DecodedInput rate(const Decoded<Reading>& read, FrameSource* frames);
  /// The torque rule.
  DecodedInput torque(const Decoded<Reading>& read, FrameSource* frames);
  /// The rates' accelerometer, through the mount the rate took.
  static std::optional<BodyVector> acceleration(const std::optional<Reading>& f_S,
                                                const DecodedInput& rate);

  DecoderFrames frames_;
  FrameIds frame_ids_;
  std::string mount_frame_;  // empty: no mount looked up yet
  Eigen::Quaterniond q_BS_ = Eigen::Quaterniond::Identity();
  std::string mag_frame_;  // empty: no mount of the field's own looked up yet
  Eigen::Quaterniond q_BM_ = Eigen::Quaterniond::Identity();
  bool mag_settled_ = false;
  TopicType twist_type_;
  TopicType torque_type_;
  std::vector<std::uint8_t> buffer_;
  geometry_msgs::Twist twist_;
  geometry_msgs::TwistStamped twist_stamped_;
  geometry_msgs::Wrench wrench_;
  geometry_msgs::WrenchStamped wrench_stamped_;
};

}  // namespace attitude_propagator
