// Absolute attitude fixes (the `orientation_fix` topic) as AttitudeEngine::submitFix takes them:
// q_WB and its error covariance R_B in the body frame, or a named refusal, counted here once.
// Shared by the node and the bag tools, like the other decoders (input_decoders.h).
//
// The rules (docs/design.md §5.4, §6.9, §7.5):
// - types: geometry_msgs/PoseWithCovarianceStamped, PoseStamped, QuaternionStamped and
//   sensor_msgs/Imu; the topic takes the type of its first message (TopicType), others are
//   WrongType. An Imu whose orientation_covariance[0] is -1 carries no orientation (REP-145):
//   NoOrientation;
// - frames: a pose or quaternion gives q_HF, the orientation of the fix frame F (`fix_frame`,
//   empty: body_frame) in its header frame H (empty: fixed_frame); an Imu gives the orientation
//   of its own frame F (header.frame_id; empty: fix_frame) in fixed_frame (REP-145: H is the
//   fixed frame). Then q_WB = q_WH q_HF q_FB, with q_WH = lookupTransform(fixed_frame, H) and
//   q_BF = lookupTransform(body_frame, F), both at the latest time (a static transform holds
//   at every time); unknown: NoTransform naming the frame;
// - covariance: PoseWithCovariance's rotation block (rows and columns 3-5 of the 6x6, "rotation
//   about X, Y, Z", the header frame's fixed axes: a left perturbation q_HF' = Exp(e_H) q_HF)
//   becomes R_B = C_BH R_H C_BHᵀ with q_BH = q_WBᶜ q_WH (e_B = C_BH e_H); an Imu's
//   orientation_covariance is in its own frame's axes (as the node's imu/data writes it):
//   R_B = C_BF R_F C_BFᵀ. PoseStamped, QuaternionStamped and an all-zero covariance carry none:
//   zero, which the engine takes as fix_stddev^2 I. A covariance that is not one
//   (checkRateCovariance) is handed on unrotated, so the engine refuses and counts it
//   (fixes_bad_covariance): a rotation could hide a negative variance;
// - the quaternion is not judged here: a non-finite or non-unit one stays so through the
//   composition, and the engine refuses and counts it (fixes_bad_quaternion);
// - stamps: a zero stamp means the arrival time; none at all: NoTime.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <boost/array.hpp>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>

#include <Eigen/Geometry>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/messages/frame_ids.h"
#include "attitude_propagator/messages/frame_source.h"
#include "attitude_propagator/messages/input_decoders.h"

namespace attitude_propagator {

/// The frames the fix rules name.
struct FixFrames {
  std::string fixed;  ///< fixed_frame
  std::string body;   ///< body_frame
  std::string fix;    ///< fix_frame: the frame whose orientation a fix measures; empty: body
  static FixFrames of(const NodeConfig& config);
};

/// A fix for AttitudeEngine::submitFix.
struct Fix {
  Stamp stamp = 0;
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  ///< not normalised
  Eigen::Matrix3d R_B = Eigen::Matrix3d::Zero();  ///< rad^2, body frame; zero: none given
};

/// Fixes refused before the engine, by reason; the engine counts what it refuses (fixes_*).
struct FixRefusals {
  std::uint64_t no_tf = 0;           ///< fixes_refused_no_tf: a frame unknown to tf
  std::uint64_t type = 0;            ///< fixes_refused_type: not the topic's type
  std::uint64_t no_time = 0;         ///< fixes_refused_no_time: no stamp and no ROS time
  std::uint64_t no_orientation = 0;  ///< fixes_refused_no_orientation: REP-145 Imu
  std::uint64_t body_frame = 0;      ///< fixes_refused_body_frame: header frame is body_frame
  std::uint64_t total() const { return no_tf + type + no_time + no_orientation + body_frame; }
};
/// The counter a fix's refusal is counted in: fixes_refused_no_tf, _type, _no_time,
/// _no_orientation, _body_frame.
const char* fixRefusedCounter(Refused why);

/// The orientation block of a 6x6 pose covariance (row-major; x, y, z, then the rotations
/// about X, Y, Z): rows and columns 3-5.
Eigen::Matrix3d orientationBlock(const boost::array<double, 36>& covariance);

/// Messages lost before they reached the node (a subscriber queue that overflowed, a dropped
/// connection), counted from the gaps in each publisher's header.seq: a stamped message's seq
/// goes up by one per message its publisher sends (rospy numbers every message; a roscpp
/// sender numbers them only if it fills seq itself). A seq at or below the publisher's last (a
/// restarted publisher, a sender that leaves seq 0) is no gap. At most kMaxPublishers are
/// remembered; a new one beyond them forgets the one heard from longest ago.
class SequenceGaps {
 public:
  static constexpr std::size_t kMaxPublishers = 64;
  /// Notes message `seq` from `publisher`; returns the messages lost just before it.
  std::uint64_t observe(const std::string& publisher, std::uint32_t seq);
  /// Every message lost so far.
  std::uint64_t lost() const { return lost_; }

 private:
  struct Last {
    std::string publisher;
    std::uint32_t seq;
    std::uint64_t heard;  // the count of messages observed when last heard
  };
  std::vector<Last> last_;
  std::uint64_t observed_ = 0;
  std::uint64_t lost_ = 0;
};

/// The header.seq of a serialised stamped message (its first field: every type a fix or a rate
/// is read from begins with a std_msgs/Header), or nothing when it is too short.
std::optional<std::uint32_t> headerSeq(const std::uint8_t* data, std::size_t size);

class FixDecoder {
 public:
  explicit FixDecoder(FixFrames frames);

  /// `frames` is asked only when a frame is neither fixed_frame (H) nor body_frame (F); it may
  /// be null (then such a fix is NoTransform). Every refusal is counted in refusals().
  Decoded<Fix> fix(const geometry_msgs::PoseWithCovarianceStamped& msg, const ros::Time& arrival,
                   FrameSource* frames);
  Decoded<Fix> fix(const geometry_msgs::PoseStamped& msg, const ros::Time& arrival,
                   FrameSource* frames);
  Decoded<Fix> fix(const geometry_msgs::QuaternionStamped& msg, const ros::Time& arrival,
                   FrameSource* frames);
  Decoded<Fix> fix(const sensor_msgs::Imu& msg, const ros::Time& arrival, FrameSource* frames);

  /// A fix as it arrives on the topic (ShapeShifter in the node, rosbag::MessageInstance in a
  /// bag): the type rule, then fix().
  template <class Serialized>
  Decoded<Fix> topic(const Serialized& m, const ros::Time& arrival, FrameSource* frames) {
    if (auto refused = type_.admit(m.getDataType(), m.getMD5Sum())) return refuse(*refused);
    if (type_.is<geometry_msgs::PoseWithCovarianceStamped>()) {
      return decode(m, pose_covariance_, arrival, frames);
    }
    if (type_.is<geometry_msgs::PoseStamped>()) return decode(m, pose_, arrival, frames);
    if (type_.is<geometry_msgs::QuaternionStamped>()) {
      return decode(m, quaternion_, arrival, frames);
    }
    return decode(m, imu_, arrival, frames);
  }

  const FixFrames& frames() const { return frames_; }
  const TopicType& type() const { return type_; }
  const FixRefusals& refusals() const { return refusals_; }
  /// The warnings of frame ids with a leading '/' met since the last call (one per frame).
  std::vector<std::string> takeFrameWarnings() { return frame_ids_.takeWarnings(); }

 private:
  /// Which axes a message's rotation covariance is about.
  enum class CovarianceAxes { Header, Fix };
  template <class Serialized, class M>
  Decoded<Fix> decode(const Serialized& m, M& scratch, const ros::Time& arrival,
                      FrameSource* frames) {
    deserializeInto(m, buffer_, scratch);
    return fix(scratch, arrival, frames);
  }
  /// Counts the refusal once and returns it.
  Decoded<Fix> refuse(Refusal refusal);
  /// The frame rules: q_HF measured at the header stamp, R in `axes`.
  Decoded<Fix> compose(const ros::Time& header_stamp, const ros::Time& arrival,
                       const std::string& header_frame, const std::string& fix_frame,
                       const Eigen::Quaterniond& q_HF, const Eigen::Matrix3d& R,
                       CovarianceAxes axes, FrameSource* frames);
  /// q_target,source, or NoTransform naming `source`.
  std::optional<Eigen::Quaterniond> lookup(const std::string& target, const std::string& source,
                                           FrameSource* frames, Refusal& refused) const;

  FixFrames frames_;
  FrameIds frame_ids_;
  TopicType type_;
  FixRefusals refusals_;
  std::vector<std::uint8_t> buffer_;
  geometry_msgs::PoseWithCovarianceStamped pose_covariance_;
  geometry_msgs::PoseStamped pose_;
  geometry_msgs::QuaternionStamped quaternion_;
  sensor_msgs::Imu imu_;
};

}  // namespace attitude_propagator
