// Reading bags: opening them with one clear error each (after the structure check, bag_check.h),
// several bags read as one stream, the topics and their types, and the loop that visits every
// message. A message is decoded, and an unstamped one stamped, by the message layer's rules
// (input_decoders.h: deserializeInto, stampOf), as the node does.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "attitude_propagator/messages/conversions.h"
#include "interrupts.h"
#include "progress.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

/// Opens `path` for reading. A missing, truncated, damaged or unindexed file throws ToolError
/// saying which, and what to do about it. The file's structure is checked first
/// (bag_check.h), so that rosbag's reader, which trusts the lengths and offsets it reads, only
/// ever sees a well-formed bag.
void openBag(rosbag::Bag& bag, const std::string& path);

/// The input bags, read as one stream: rosbag::View merges the messages of all of them by
/// record time (a query per bag), so the parts of a split recording (`rosbag record --split`)
/// read as the recording itself, in whatever order they are given.
class BagSet {
 public:
  /// Opens every path with openBag, so each is checked before rosbag reads any. The same file
  /// twice under any name (a symlink, a hard link, "./a.bag") is a UsageError: each of its
  /// messages would arrive twice.
  explicit BagSet(const std::vector<std::string>& paths);
  BagSet(const BagSet&) = delete;
  BagSet& operator=(const BagSet&) = delete;

  const std::vector<std::string>& paths() const { return paths_; }
  std::size_t size() const { return bags_.size(); }
  rosbag::Bag& bag(std::size_t i) { return *bags_[i]; }
  /// The inputs for messages: "a.bag", or "a.bag, b.bag".
  std::string name() const;
  /// Adds to `view` a query for `topics` in every bag (each under its spelling in that bag).
  void addQuery(rosbag::View& view, const std::vector<std::string>& topics);
  /// Pairs of bags whose messages on `topics` overlap in record time, described for a warning
  /// ("a.bag and b.bag share 10.0 s"); empty for the parts of one recording.
  std::vector<std::string> overlaps(const std::vector<std::string>& topics);

 private:
  std::vector<std::string> paths_;
  std::vector<std::unique_ptr<rosbag::Bag>> bags_;
};

/// The bags' topics with their types, " /a (type), /b (type)", for one-line error messages.
std::string describeTopics(BagSet& bags);

/// The datatype of `topic` in the bags (a leading '/' optional on either side), or nothing.
/// Throws ToolError when the topic carries more than one type.
std::optional<std::string> topicType(BagSet& bags, const std::string& topic);

/// One topic under two spellings ("imu" and "/imu": rosbag records either), without copying.
inline bool sameTopic(const std::string& a, const std::string& b) {
  if (a == b) return true;
  if (!a.empty() && a[0] == '/') return a.compare(1, std::string::npos, b) == 0;
  return !b.empty() && b[0] == '/' && b.compare(1, std::string::npos, a) == 0;
}

/// Throws ToolError unless `topic` is in the bags with one of `accepted` (datatype and MD5)
/// and has messages in one of them at least (a part of a split recording may lack a topic).
/// Returns the datatype found.
std::string requireTopic(BagSet& bags, const std::string& topic, const char* role,
                         const std::vector<std::pair<std::string, std::string>>& accepted);

/// Messages on `topics` in the bags.
std::uint64_t messageCount(BagSet& bags, const std::vector<std::string>& topics);

template <class M>
std::pair<std::string, std::string> typeOf() {
  return {ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>()};
}

template <class M>
bool isType(const rosbag::MessageInstance& m) {
  return m.getDataType() == ros::message_traits::datatype<M>() &&
         m.getMD5Sum() == ros::message_traits::md5sum<M>();
}

/// Visits every message of `view` in order, counting into `count`, with the progress line and
/// a check for Ctrl-C every 1024 messages. A bag found damaged mid-way (rosbag's exceptions, a
/// message that does not deserialise) is one ToolError that names `input` and how far it got;
/// the tool's own errors (ToolError, e.g. a full disk) pass unchanged.
template <class Visit>
void visitMessages(rosbag::View& view, const std::string& input, Progress& progress,
                   std::uint64_t& count, Visit visit) {
  auto damaged = [&](const char* what) {
    progress.finish();
    return ToolError(input + ": damaged after " + std::to_string(count) + " messages (" + what +
                     ")");
  };
  try {
    for (const rosbag::MessageInstance& m : view) {
      visit(m);
      progress.update(++count);
      if ((count & 1023u) == 0) throwIfInterrupted();
    }
  } catch (const ToolError&) {
    progress.finish();
    throw;
  } catch (const std::bad_alloc&) {
    throw damaged("a length in it asks for more memory than there is");
  } catch (const std::exception& e) {
    // rosbag::BagException, ros::serialization::StreamOverrunException and the like.
    throw damaged(e.what());
  }
  throwIfInterrupted();
}

}  // namespace tools
}  // namespace attitude_propagator
