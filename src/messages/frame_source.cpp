#include "attitude_propagator/messages/frame_source.h"

#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>

#include "attitude_propagator/messages/conversions.h"

namespace attitude_propagator {

std::optional<Eigen::Quaterniond> BufferCoreFrames::rotation(const std::string& target,
                                                             const std::string& source,
                                                             const ros::Time& stamp,
                                                             std::string* error) {
  std::string why;
  if (!buffer_.canTransform(target, source, stamp, &why)) {
    if (error) *error = why;
    return std::nullopt;
  }
  try {
    return rotationOf(buffer_.lookupTransform(target, source, stamp)).normalized();
  } catch (const tf2::TransformException& e) {  // the tree changed in between (a listener)
    if (error) *error = e.what();
    return std::nullopt;
  }
}

}  // namespace attitude_propagator
