#include "attitude_propagator/ros/tf_conflict_watch.h"

namespace attitude_propagator {

void TfConflictWatch::sent(const geometry_msgs::TransformStamped& t) {
  const std::uint64_t ns = t.header.stamp.toNSec();
  own_stamps_.push_back(ns);
  own_set_.insert(ns);
  if (own_stamps_.size() > kOwnStampsKept) {
    own_set_.erase(own_set_.find(own_stamps_.front()));
    own_stamps_.pop_front();
  }
}

std::optional<LogLine> TfConflictWatch::onTfSeen(const tf2_msgs::TFMessage& msg,
                                                 const std::string& publisher, bool named_like_us,
                                                 bool latched, const Parameters& p,
                                                 const ros::WallTime& now) {
  const std::string& child = p.reverse_tf ? p.fixed_frame : p.body_frame;
  const std::string& parent = p.reverse_tf ? p.body_frame : p.fixed_frame;
  for (const auto& t : msg.transforms) {
    if (t.child_frame_id != child) continue;
    const bool ours = named_like_us && !latched && t.header.frame_id == parent &&
                      own_set_.count(t.header.stamp.toNSec()) > 0;
    if (ours) continue;
    ++tf_conflicts_;
    const bool stop = p.tf_conflict == "stop";
    if (stop) {
      if (latched) tf_conflict_latched_ = true;
      if (!latched) last_tf_conflict_ = now;
    }
    std::optional<LogLine> line;
    // warn: once. stop: at each stop, so a conflict that comes back is named again.
    if (stop ? !tf_stopped_ : tf_conflicts_ == 1) {
      line = LogLine{
          ros::console::levels::Warn, "",
          formatted(
              "tf: %s%s also publishes '%s' as the child of '%s' on %s (we publish %s -> %s): a "
              "frame has one parent. Publish our transform to a frame of its own "
              "(body_frame:=%s_attitude), or reverse_tf:=true for a tree rooted at the body, or "
              "publish_tf:=false%s",
              named_like_us ? "another nodelet in manager " : "", logText(publisher).c_str(),
              child.c_str(), logText(t.header.frame_id).c_str(), latched ? "/tf_static" : "/tf",
              parent.c_str(), child.c_str(), child.c_str(),
              !stop     ? "; tf_conflict:=stop would stop our tf instead"
              : latched ? "; tf_conflict is stop: no tf from this node until publish_tf is "
                          "switched off and on"
                        : "; tf_conflict is stop: no tf from this node until no other parent "
                          "has been seen on /tf for 2 s, or publish_tf is switched off and on")};
    }
    if (stop) tf_stopped_ = true;
    return line;
  }
  return std::nullopt;
}

std::optional<LogLine> TfConflictWatch::resumeTfIfClear(const Parameters& p,
                                                        const ros::WallTime& now) {
  if (!tf_stopped_ || tf_conflict_latched_) return std::nullopt;
  if ((now - last_tf_conflict_).toSec() < kTfConflictClearance) return std::nullopt;
  return resumeTf("no other parent on /tf for 2 s", p);
}

std::optional<LogLine> TfConflictWatch::resumeTf(const char* why, const Parameters& p) {
  tf_conflict_latched_ = false;
  if (!tf_stopped_) return std::nullopt;
  tf_stopped_ = false;
  ++tf_resumes_;
  return LogLine{ros::console::levels::Info, "",
                 formatted("tf: %s: publishing %s -> %s again", why,
                           (p.reverse_tf ? p.body_frame : p.fixed_frame).c_str(),
                           (p.reverse_tf ? p.fixed_frame : p.body_frame).c_str())};
}

}  // namespace attitude_propagator
