#include "attitude_propagator/messages/fix_decoder.h"

#include <algorithm>
#include <utility>

#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/input_roles.h"
#include "attitude_propagator/messages/refusal_table.h"

namespace attitude_propagator {

FixFrames FixFrames::of(const NodeConfig& config) {
  const Parameters& p = config.parameters;
  return {p.fixed_frame, p.body_frame, p.fix_frame};
}

const char* fixRefusedCounter(Refused why) {
  const char* counter = refusalRow(why).fix_counter;
  return counter ? counter : "?";  // "?": not a fix's refusal
}

Eigen::Matrix3d orientationBlock(const boost::array<double, 36>& covariance) {
  using Matrix6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  return Eigen::Map<const Matrix6>(covariance.data()).bottomRightCorner<3, 3>();
}

std::uint64_t SequenceGaps::observe(const std::string& publisher, std::uint32_t seq) {
  ++observed_;
  auto it = std::find_if(last_.begin(), last_.end(),
                         [&](const Last& l) { return l.publisher == publisher; });
  if (it == last_.end()) {
    if (last_.size() >= kMaxPublishers) {
      last_.erase(std::min_element(last_.begin(), last_.end(),
                                   [](const Last& a, const Last& b) { return a.heard < b.heard; }));
    }
    last_.push_back({publisher, seq, observed_});
    return 0;
  }
  const std::uint64_t gap = seq > it->seq ? std::uint64_t{seq} - it->seq - 1 : 0;
  it->seq = seq;
  it->heard = observed_;
  lost_ += gap;
  return gap;
}

std::optional<std::uint32_t> headerSeq(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < 4) return std::nullopt;
  return std::uint32_t{data[0]} | std::uint32_t{data[1]} << 8 | std::uint32_t{data[2]} << 16 |
         std::uint32_t{data[3]} << 24;  // ROS serialises little-endian
}

FixDecoder::FixDecoder(FixFrames frames)
    : frames_(std::move(frames)), type_(TopicType::accepting(inputRoleOf(InputRole::Fix).types)) {}

Decoded<Fix> FixDecoder::refuse(Refusal refusal) {
  const RefusalRow& row = refusalRow(refusal.why);
  if (row.fix_count) ++(refusals_.*row.fix_count);
  return {std::nullopt, std::move(refusal)};
}

Decoded<Fix> FixDecoder::fix(const geometry_msgs::PoseWithCovarianceStamped& msg,
                             const ros::Time& arrival, FrameSource* frames) {
  return compose(msg.header.stamp, arrival, msg.header.frame_id, frames_.fix,
                 toEigen(msg.pose.pose.orientation), orientationBlock(msg.pose.covariance),
                 CovarianceAxes::Header, frames);
}

Decoded<Fix> FixDecoder::fix(const geometry_msgs::PoseStamped& msg, const ros::Time& arrival,
                             FrameSource* frames) {
  return compose(msg.header.stamp, arrival, msg.header.frame_id, frames_.fix,
                 toEigen(msg.pose.orientation), Eigen::Matrix3d::Zero(), CovarianceAxes::Header,
                 frames);
}

Decoded<Fix> FixDecoder::fix(const geometry_msgs::QuaternionStamped& msg, const ros::Time& arrival,
                             FrameSource* frames) {
  return compose(msg.header.stamp, arrival, msg.header.frame_id, frames_.fix,
                 toEigen(msg.quaternion), Eigen::Matrix3d::Zero(), CovarianceAxes::Header, frames);
}

Decoded<Fix> FixDecoder::fix(const sensor_msgs::Imu& msg, const ros::Time& arrival,
                             FrameSource* frames) {
  // REP-145: orientation_covariance[0] == -1 says the message carries no orientation.
  if (msg.orientation_covariance[0] == -1.0) {
    Refusal r;
    r.why = Refused::NoOrientation;
    r.frame = msg.header.frame_id;
    return refuse(std::move(r));
  }
  // The orientation of the Imu's own frame in the fixed frame (REP-145).
  const std::string& own = msg.header.frame_id.empty() ? frames_.fix : msg.header.frame_id;
  return compose(msg.header.stamp, arrival, frames_.fixed, own, toEigen(msg.orientation),
                 covarianceFromMsg(msg.orientation_covariance), CovarianceAxes::Fix, frames);
}

std::optional<Eigen::Quaterniond> FixDecoder::lookup(const std::string& target,
                                                     const std::string& source, FrameSource* frames,
                                                     Refusal& refused) const {
  if (source == target) return Eigen::Quaterniond::Identity();
  std::string error = "no frame source";
  auto q = frames ? frames->rotation(target, source, ros::Time(), &error) : std::nullopt;
  if (!q) {
    refused.why = Refused::NoTransform;
    refused.frame = source;
    refused.detail = error;
  }
  return q;
}

Decoded<Fix> FixDecoder::compose(const ros::Time& header_stamp, const ros::Time& arrival,
                                 const std::string& header_frame, const std::string& fix_frame,
                                 const Eigen::Quaterniond& q_HF, const Eigen::Matrix3d& R,
                                 CovarianceAxes axes, FrameSource* frames) {
  Refusal refused;
  const auto stamp = stampOf(header_stamp, arrival);
  if (!stamp) {
    refused.why = Refused::NoTime;
    return refuse(std::move(refused));
  }
  // The frame id rule (frame_ids.h): a leading '/' removed; a space or line break refused.
  const auto header_id = frame_ids_.admit(header_frame);
  const auto fix_id = frame_ids_.admit(fix_frame);
  if (!header_id || !fix_id) {
    refused.why = Refused::NoTransform;
    refused.frame = header_id ? fix_frame : header_frame;
    refused.detail = kFrameIdRule;
    return refuse(std::move(refused));
  }
  const std::string& H = header_id->empty() ? frames_.fixed : *header_id;
  const std::string& F = fix_id->empty() ? frames_.body : *fix_id;
  if (H == frames_.body) {
    // q_WH would be the node's own output (fixed -> body on tf): the fix would correct the
    // state by the state itself.
    refused.why = Refused::FixBodyFrame;
    refused.frame = H;
    return refuse(std::move(refused));
  }
  const auto q_WH = lookup(frames_.fixed, H, frames, refused);
  if (!q_WH) return refuse(std::move(refused));
  const auto q_BF = lookup(frames_.body, F, frames, refused);
  if (!q_BF) return refuse(std::move(refused));

  Fix fix;
  fix.stamp = *stamp;
  // q_WB = q_WH q_HF q_FB. q_HF is not normalised: the engine judges its norm.
  fix.q_WB = *q_WH * q_HF * q_BF->conjugate();
  if (R.isZero(0.0) || checkRateCovariance(R) != RateCovarianceCheck::Ok) {
    fix.R_B = R;  // none given; or not a covariance, which the engine refuses as given
  } else if (axes == CovarianceAxes::Header) {
    // An error about H's fixed axes, q_HF' = Exp(e_H) q_HF, is e_B = C_BH e_H in the body,
    // q_BH = q_WBᶜ q_WH = q_BF q_HFᶜ.
    const Eigen::Quaterniond q_BH = *q_BF * q_HF.normalized().conjugate();
    fix.R_B = rotateCovariance(R, q_BH.toRotationMatrix());
  } else {
    fix.R_B = rotateCovariance(R, q_BF->toRotationMatrix());  // e_B = C_BF e_F
  }
  return {std::move(fix), std::nullopt};
}

}  // namespace attitude_propagator
