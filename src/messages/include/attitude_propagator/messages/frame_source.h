// Where the decoders get the rotation between two frames: tf's tree, whoever fills it. The node
// fills a tf2_ros::Buffer from /tf and /tf_static; the bag tools fill a tf2::BufferCore from the
// bag's /tf and /tf_static. Both are a tf2::BufferCore, read through BufferCoreFrames.
#pragma once

#include <optional>
#include <string>

#include <ros/time.h>

#include <Eigen/Geometry>

namespace tf2 {
class BufferCore;
}

namespace attitude_propagator {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// q_target,source: the rotation that takes a vector given in `source` into `target`'s axes
  /// (tf's lookupTransform(target, source, stamp); a zero stamp: the latest transform), or
  /// nullopt when tf does not know it; then `error` (if given) says why, in tf's words.
  virtual std::optional<Eigen::Quaterniond> rotation(const std::string& target,
                                                     const std::string& source,
                                                     const ros::Time& stamp,
                                                     std::string* error = nullptr) = 0;
};

/// A FrameSource over a tf2::BufferCore (a tf2_ros::Buffer is one), which it only reads; the
/// rotation is normalised.
class BufferCoreFrames : public FrameSource {
 public:
  explicit BufferCoreFrames(const tf2::BufferCore& buffer) : buffer_(buffer) {}
  std::optional<Eigen::Quaterniond> rotation(const std::string& target, const std::string& source,
                                             const ros::Time& stamp,
                                             std::string* error = nullptr) override;

 private:
  const tf2::BufferCore& buffer_;
};

}  // namespace attitude_propagator
