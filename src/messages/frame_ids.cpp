#include "attitude_propagator/messages/frame_ids.h"

#include <stdexcept>

#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

const char* const kFrameIdRule =
    "a frame id may not contain spaces, tabs or line breaks (tf2 frame ids are single words; "
    "a leading '/' is removed)";

std::string tf2FrameId(const std::string& frame) {
  return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame;
}

bool frameIdRefused(const std::string& frame) {
  return frame.find_first_of(" \t\r\n\v\f") != std::string::npos;
}

namespace {

// A frame id quoted for a log line, by the one rule for text from outside (quoted_text.h):
// control characters shown as '?', a huge one cut.
std::string quoted(const std::string& frame) { return "'" + logText(frame) + "'"; }

}  // namespace

const std::string* FrameIds::admit(const std::string& frame) {
  if (frameIdRefused(frame)) return nullptr;
  if (frame.empty() || frame.front() != '/') return &frame;
  const auto known = stripped_.find(frame);
  if (known != stripped_.end()) return &known->second;
  const std::string& id = stripped_.emplace(frame, tf2FrameId(frame)).first->second;
  warnings_.push_back("frame id " + quoted(frame) + " has a leading '/' (tf1); read as " +
                      quoted(id) + " (tf2 frame ids do not start with '/')");
  return &id;
}

std::vector<std::string> FrameIds::takeWarnings() {
  std::vector<std::string> out;
  out.swap(warnings_);
  return out;
}

namespace {

void tf2FrameParameter(const std::string& name, std::string& value,
                       std::vector<std::string>& warnings) {
  if (frameIdRefused(value)) {
    throw std::invalid_argument(name + ": frame id " + quoted(value) +
                                " refused; accepted: a tf2 frame id without spaces, tabs or "
                                "line breaks (a leading '/' is removed)");
  }
  if (tf2FrameId(value).size() > kMaxFrameParameterBytes) {
    throw std::invalid_argument(
        name + ": frame id " + quoted(value) + " refused; accepted: at most " +
        std::to_string(kMaxFrameParameterBytes) + " bytes (every message published carries it)");
  }
  if (value.empty() || value.front() != '/') return;
  const std::string id = tf2FrameId(value);
  warnings.push_back(name + ": frame id " + quoted(value) + " has a leading '/' (tf1); read as " +
                     quoted(id) + " (tf2 frame ids do not start with '/')");
  value = id;
}

}  // namespace

std::string noMountText(const std::string& frame, const std::string& body,
                        const std::string& setting) {
  return "no transform from the rates' frame " + quoted(frame) + " to body_frame " + quoted(body) +
         ": publish the mount " + quoted(body) + " -> " + quoted(frame) +
         " on /tf_static, or take the IMU's own frame as the body: " + setting + logText(frame);
}

std::vector<std::string> tf2FrameParameters(Parameters& p) {
  std::vector<std::string> warnings;
  tf2FrameParameter("fixed_frame", p.fixed_frame, warnings);
  tf2FrameParameter("body_frame", p.body_frame, warnings);
  tf2FrameParameter("fix_frame", p.fix_frame, warnings);
  return warnings;
}

}  // namespace attitude_propagator
