// What the offline tools (propagate_bag, evaluate_bag_core) share: the node's parameters from
// YAML and `--set`, opening a bag and finding its topics with one clear error each, decoding a
// bag message into a reused message, a progress bar, and an output file that appears under its
// name only when complete.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"

namespace attitude_propagator {
namespace tools {

/// One clear line for the user; the tools print it and exit non-zero.
struct ToolError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------------------------------------
// Parameters: the node's, with the node's YAML (config/default.yaml and the scene files).
// ---------------------------------------------------------------------------------------------

/// Reads a YAML map of node parameters into p. Unknown names and wrong types throw
/// std::invalid_argument naming the parameter, as the node's loader does.
void loadConfigFile(const std::string& path, Parameters& p);
/// Applies one `name=value`, the value in YAML flow syntax (`cf4`, `true`, `[1, 2, 3]`).
void applySetting(const std::string& assignment, Parameters& p);

// ---------------------------------------------------------------------------------------------
// Bags
// ---------------------------------------------------------------------------------------------

/// Opens `path` for reading. A missing, truncated, damaged or unindexed file throws ToolError
/// saying which, and what to do about it.
void openBag(rosbag::Bag& bag, const std::string& path);

/// The bag's topics with their types, " /a (type), /b (type)", for one-line error messages.
std::string describeTopics(rosbag::Bag& bag);

/// The datatype of `topic` in the bag (a leading '/' optional on either side), or nothing.
/// Throws ToolError when the topic carries more than one type.
std::optional<std::string> topicType(rosbag::Bag& bag, const std::string& topic);

/// The topic's name as recorded ("imu" may be recorded as "/imu").
std::string recordedName(rosbag::Bag& bag, const std::string& topic);

/// Throws ToolError unless `topic` is in the bag with one of `accepted` (datatype and MD5).
/// Returns the datatype found.
std::string requireTopic(rosbag::Bag& bag, const std::string& topic, const char* role,
                         const std::vector<std::pair<std::string, std::string>>& accepted);

template <class M>
std::pair<std::string, std::string> typeOf() {
  return {ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>()};
}

template <class M>
bool isType(const rosbag::MessageInstance& m) {
  return m.getDataType() == ros::message_traits::datatype<M>() &&
         m.getMD5Sum() == ros::message_traits::md5sum<M>();
}

/// Deserialises a bag message into an existing message through a reused buffer: a steady
/// stream allocates nothing here (instantiate() allocates a message each time).
template <class M>
void decodeInto(const rosbag::MessageInstance& m, std::vector<std::uint8_t>& buffer, M& out) {
  const std::uint32_t size = m.size();
  buffer.resize(size);
  ros::serialization::OStream write(buffer.data(), size);
  m.write(write);
  ros::serialization::IStream read(buffer.data(), size);
  ros::serialization::deserialize(read, out);
}

inline Stamp toStamp(const ros::Time& time) { return static_cast<Stamp>(time.toNSec()); }
inline ros::Time toRosTime(Stamp stamp) {
  ros::Time time;
  time.fromNSec(static_cast<std::uint64_t>(stamp));
  return time;
}
/// A header stamp, or the record time for an unstamped message (the node's receipt time).
inline Stamp stampOr(const ros::Time& header, const ros::Time& record) {
  return toStamp(header.isZero() ? record : header);
}

// ---------------------------------------------------------------------------------------------
// Progress, interruption and outputs
// ---------------------------------------------------------------------------------------------

/// A progress line on stderr (only when it is a terminal): share done, messages per second,
/// time left. Redrawn at most ten times a second; cleared by finish().
class Progress {
 public:
  Progress(std::uint64_t total, bool enabled);
  /// Cheap enough to call per message: looks at the clock once every 1024 calls.
  void update(std::uint64_t done) {
    if (enabled_ && (done & 1023u) == 0) draw(done, false);
  }
  void finish();
  double elapsed() const;

 private:
  void draw(std::uint64_t done, bool force);
  std::uint64_t total_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

/// SIGINT and SIGTERM set a flag instead of killing the program, so a partial output can be
/// removed; throwIfInterrupted() turns it into a ToolError.
void catchInterrupts();
void throwIfInterrupted();

/// Visits every message of `view` in order, counting into `count`, with the progress line and
/// a check for Ctrl-C every 1024 messages. A bag found damaged mid-way is one ToolError that
/// names `input` and how far it got.
template <class Visit>
void visitMessages(rosbag::View& view, const std::string& input, Progress& progress,
                   std::uint64_t& count, Visit visit) {
  try {
    for (const rosbag::MessageInstance& m : view) {
      visit(m);
      progress.update(++count);
      if ((count & 1023u) == 0) throwIfInterrupted();
    }
  } catch (const rosbag::BagException& e) {
    progress.finish();
    throw ToolError(input + ": damaged after " + std::to_string(count) + " messages (" + e.what() +
                    ")");
  }
  throwIfInterrupted();
}

/// An output written under a temporary name in the same directory and renamed to its own
/// name by commit(): a failed or interrupted run leaves nothing under the name.
class PendingFile {
 public:
  explicit PendingFile(std::string path);
  ~PendingFile();  // removes the temporary file unless committed
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  const std::string& temporary() const { return temporary_; }
  const std::string& path() const { return path_; }
  void commit();

 private:
  std::string path_;
  std::string temporary_;
  bool committed_ = false;
};

/// A FILE* with a large buffer, closed by the destructor; write errors surface in close().
class CsvFile {
 public:
  explicit CsvFile(const std::string& path);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  std::FILE* get() { return file_; }
  /// Throws ToolError when anything failed to reach the disk.
  void close();

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
};

/// A bag (format 2.0) written a chunk at a time. Messages are serialised into an in-memory chunk
/// that goes to the file in one write when it passes the threshold (LZ4-compressed with
/// rosbag's own roslz4 if asked), followed by its index records; the connections and the chunk
/// list close the file. rosbag::Bag::write seeks to the end of the file twice per message, which
/// with glibc's read-write FILE costs an fstat, an lseek and a read each, plus one write per
/// message uncompressed: about six system calls per message against about two per chunk here.
/// Memory: one chunk and its index, and a few bytes per chunk. The file is laid out as
/// rosbag::Bag lays it out (the same records, header padding and chunk threshold), so rosbag's
/// readers, `rosbag info` and `rosbag reindex` take it as their own.
class BagOutput {
 public:
  enum class Compression { None, Lz4 };
  static constexpr std::uint32_t kChunkThreshold = 768 * 1024;  // rosbag's default

  BagOutput(const std::string& path, Compression compression,
            std::uint32_t chunk_threshold = kChunkThreshold);
  ~BagOutput();
  BagOutput(const BagOutput&) = delete;
  BagOutput& operator=(const BagOutput&) = delete;

  /// Appends `msg` on `topic` at record time `time` (at least ros::TIME_MIN).
  template <class M>
  void write(const std::string& topic, const ros::Time& time, const M& msg) {
    const std::uint32_t id =
        connection(topic, ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>(),
                   ros::message_traits::definition<M>());
    const std::uint32_t length = ros::serialization::serializationLength(msg);
    ros::serialization::OStream out(beginMessage(id, time, length), length);
    ros::serialization::serialize(out, msg);
    if (chunk_.size() > threshold_) writeChunk();
  }
  /// Writes the last chunk and the index; throws ToolError when anything failed to reach the
  /// disk.
  void close();

 private:
  struct Connection {
    std::string topic, datatype, md5sum, definition;
    std::vector<std::uint8_t> index;  // this chunk's (time, offset) entries, as recorded
    std::uint32_t count = 0;          // messages in this chunk
  };
  struct ChunkInfo {
    std::uint64_t position;
    ros::Time start, end;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> counts;  // (connection, messages)
  };
  std::uint32_t connection(const std::string& topic, const char* datatype, const char* md5sum,
                           const char* definition);
  std::uint8_t* beginMessage(std::uint32_t id, const ros::Time& time, std::uint32_t length);
  void writeChunk();
  void writeHeader(std::uint64_t index_position);
  void put(const std::vector<std::uint8_t>& bytes);

  std::string path_;
  std::FILE* file_ = nullptr;
  Compression compression_;
  std::uint32_t threshold_;
  std::uint64_t position_ = 0;  // bytes written so far
  bool failed_ = false;
  bool chunk_open_ = false;
  std::vector<Connection> connections_;
  std::vector<std::uint8_t> chunk_;  // the open chunk's records, uncompressed
  std::vector<std::uint8_t> out_;    // what goes to the file next
  std::vector<char> compressed_;
  ros::Time chunk_start_, chunk_end_;
  std::vector<ChunkInfo> chunks_;
};

/// A stamp as seconds with nanosecond digits ("1700000000.005000000"), exact.
std::string formatStamp(Stamp stamp);

/// Command-line reading: the value after option `argv[i]`, or ToolError.
std::string optionValue(int argc, char** argv, int& i);
double parseNumber(const std::string& option, const std::string& text);

}  // namespace tools
}  // namespace attitude_propagator
