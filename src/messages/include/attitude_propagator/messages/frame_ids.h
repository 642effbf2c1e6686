// Frame ids as drivers write them, made tf2's. tf1 named frames with a leading '/' (`/imu`),
// and many drivers and launch files still do; tf2 refuses such a name in every lookup and logs
// an error per call. The rule, for every input's frame_id (rates, torques, bias, fixes) and
// every frame parameter (body_frame, fixed_frame, fix_frame):
// - one leading '/' is removed: `/imu` is `imu` (tf2's own setTransform strips it so from /tf);
// - a frame id with a space, tab or line break is refused: no tf2 frame has one, and a log line
//   naming it would be broken or misleading.
// The first time a frame with a leading '/' is met a warning names it, once per frame.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "attitude_propagator/config/parameters.h"

namespace attitude_propagator {

/// The rule a refused frame id breaks, in words for a log line.
extern const char* const kFrameIdRule;

/// `frame` without its leading '/' (tf1's convention); as it is otherwise.
std::string tf2FrameId(const std::string& frame);

/// Whether `frame` holds a space, tab or line break (refused: kFrameIdRule).
bool frameIdRefused(const std::string& frame);

/// The frame ids one reader meets, made tf2's, with one warning per frame that had a '/'.
class FrameIds {
 public:
  /// tf2FrameId(frame), or null when the frame is refused (frameIdRefused). A frame with a
  /// leading '/' met for the first time queues a warning naming it (takeWarnings). Points at
  /// `frame` itself or at a name kept here: a steady stream allocates nothing.
  const std::string* admit(const std::string& frame);
  /// The warnings queued since the last call, oldest first.
  std::vector<std::string> takeWarnings();
  bool hasWarnings() const { return !warnings_.empty(); }

 private:
  std::map<std::string, std::string> stripped_;  // with its '/' -> without
  std::vector<std::string> warnings_;
};

/// Why rates in `frame` reach no body and what to change, naming both frames: publish the
/// mount body_frame -> frame, or take the sensor's own frame as the body (what a user with only
/// an IMU wants); `setting` is how the caller's user sets body_frame, up to the value
/// (`--set body_frame=` in the bag tools, `body_frame:=` for the node's launch files). Both
/// frames are quoted by the one rule for text from outside (quoted_text.h): pass them as they
/// came, not already cut.
std::string noMountText(const std::string& frame, const std::string& body,
                        const std::string& setting);

/// Longest frame parameter accepted (bytes): every message the node or propagate_bag publishes
/// carries fixed_frame or body_frame, so a frame of 100 kB makes every output message 100 kB
/// (a bag of 11 000 states 2.2 GB, written 150 times slower). Real tf frame ids are a few tens.
constexpr std::size_t kMaxFrameParameterBytes = 256;

/// The frame parameters (fixed_frame, body_frame, fix_frame) made tf2's in place, before
/// validateParameters: a leading '/' removed, with one warning each naming the parameter and
/// both spellings (returned); a frame with a space or line break, or longer than
/// kMaxFrameParameterBytes, throws std::invalid_argument naming the parameter and the rule, as
/// validateParameters does for its refusals.
std::vector<std::string> tf2FrameParameters(Parameters& p);

}  // namespace attitude_propagator
