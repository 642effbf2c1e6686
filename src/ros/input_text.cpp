#include "attitude_propagator/ros/input_text.h"

#include "attitude_propagator/limits.h"

namespace attitude_propagator {

namespace {

std::string refusalText(const Refusal& r, const char* topic, bool torque, const EngineCounters& c,
                        const std::string& body, const InputDecoders& decoders) {
  if (r.detail == kFrameIdRule) {
    return formatted("%s: frame id '%s' refused; %s", topic, logText(r.frame).c_str(),
                     kFrameIdRule);
  }
  switch (r.why) {
    case Refused::NoRate:
      return formatted(
          "%s: angular_velocity_covariance[0] == -1 (no rate, REP-145): rejected (%lu so far)",
          topic, c.rejected_no_rate);
    case Refused::BadCovariance:
      return formatted(
          "%s: angular_velocity_covariance rejected (%s; accepted: symmetric, variances in [0, "
          "%g] rad^2/s^2) (%lu so far)",
          topic, rateCovarianceCheckName(r.check), kMaxRateVariance, c.rejected_covariance);
    case Refused::WrongType: {
      const TopicType& type = torque ? decoders.torqueType() : decoders.twistType();
      return formatted(
          "%s: message type %s rejected; the topic carries %s (its first message's type; "
          "accepted: %s or %s) (%lu rejected so far)",
          topic, logText(r.detail).c_str(),
          type.datatype().empty() ? "nothing yet" : type.datatype().c_str(),
          type.plainType().c_str(), type.stampedType().c_str(), c.rejected_type);
    }
    case Refused::NoTransform:
      if (torque) {
        return formatted("torque in frame '%s': no transform to '%s' yet: dropped (%s)",
                         logText(r.frame).c_str(), body.c_str(),
                         logText(r.detail, 4 * kLogTextBytes).c_str());
      }
      if (std::string(topic) == "imu/mag") {
        // The field's own mount: the rates' advice (body_frame:=) would not be the fix.
        return formatted(
            "imu/mag: no transform from the field's frame '%s' to body_frame '%s': "
            "publish the mount on /tf_static; dropped (%lu so far; %s)",
            logText(r.frame).c_str(), body.c_str(), c.dropped_no_tf,
            logText(r.detail, 4 * kLogTextBytes).c_str());
      }
      return formatted("%s: %s; dropped %lu messages so far (%s)", topic,
                       noMountText(r.frame, body, "body_frame:=").c_str(), c.dropped_no_tf,
                       logText(r.detail, 4 * kLogTextBytes).c_str());
    case Refused::NoTime:
      // An unstamped message under sim time before the first /clock: no time to put it at.
      return formatted("%s: unstamped message and no ROS time yet (/clock): dropped", topic);
    case Refused::BiasFrame:
      return formatted(
          "gyro_bias: frame '%s' rejected; accepted: '%s' (the body), the rate messages' frame "
          "once known, or empty (%lu rejected so far)",
          logText(r.frame).c_str(), body.c_str(), c.rejected_bias);
    case Refused::NoOrientation:
    case Refused::FixBodyFrame:
      break;  // fixes only: fix_input.cpp
  }
  return {};
}

}  // namespace

std::optional<LogLine> refusalText(const Refusal& r, const std::string& topic,
                                   const EngineCounters& c, const std::string& body,
                                   const InputDecoders& decoders) {
  if (r.why == Refused::NoOrientation || r.why == Refused::FixBodyFrame) {
    return std::nullopt;  // fixes only: fix_input.cpp
  }
  const bool torque = topic == "torque";
  // One throttle per kind, and the torque's missing transform apart from the rates'.
  const std::string kind = "refused " + std::to_string(static_cast<int>(r.why)) +
                           (torque && r.why == Refused::NoTransform ? " torque" : "");
  return LogLine{ros::console::levels::Warn, kind,
                 refusalText(r, topic.c_str(), torque, c, body, decoders)};
}

std::string mountText(const std::string& frame, const std::string& body,
                      const Eigen::Quaterniond& q) {
  return formatted("rates in frame '%s' are rotated into '%s' by q = [%g, %g, %g, %g] (x y z w)",
                   logText(frame).c_str(), body.c_str(), q.x(), q.y(), q.z(), q.w());
}

LogLine biasRejectedText(const EngineCounters& c) {
  return {ros::console::levels::Warn, "bias rejected",
          formatted("gyro_bias: non-finite or larger than %g rad/s: rejected (%lu so far)",
                    kMaxBodyRate, c.rejected_bias)};
}

}  // namespace attitude_propagator
