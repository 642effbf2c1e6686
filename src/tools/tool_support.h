// What the offline tools (propagate_bag, evaluate_bag_core) share: the node's parameters from
// YAML and `--set`, opening a bag and finding its topics with one clear error each, decoding a
// bag message into a reused message, a progress bar, and an output file that appears under its
// name only when complete, never over an input and never past a full disk; the exit codes.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/conversions.h"

namespace attitude_propagator {
namespace tools {

/// The tools' exit codes (their --help and docs/bag_tools.md list them). A signal that stops a run
/// exits with 128 + its number, as a shell reports a process the signal killed (130: Ctrl-C).
enum ExitCode : int {
  kExitOk = 0,             ///< the inputs were used and every output is complete
  kExitFailed = 1,         ///< an input could not be read (missing, damaged) or an output written
  kExitUsage = 2,          ///< bad options or parameters, an output that is an input
  kExitNothingUsable = 3,  ///< the run completed but produced nothing usable (says why)
};

/// One clear line for the user; the tools print it and exit with `code`.
struct ToolError : std::runtime_error {
  explicit ToolError(const std::string& what, int code = kExitFailed)
      : std::runtime_error(what), exit_code(code) {}
  int exit_code;
};

/// A command line the tool cannot run: exit code 2.
struct UsageError : ToolError {
  explicit UsageError(const std::string& what) : ToolError(what, kExitUsage) {}
};

/// main() of a tool: runs `run`, and turns every exception into one line "name: what" on
/// stderr and its exit code (std::invalid_argument, the parameters' refusal, is a usage error).
int runTool(const char* name, int (*run)(int, char**), int argc, char** argv);

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

/// A TFMessage's transform count is checked against the message's size first: deserialising
/// makes room for that many transforms before reading them, and a damaged count would ask for
/// up to 2^32 of them. A transform takes at least 76 bytes (header: seq, stamp and an empty
/// frame_id; an empty child_frame_id; translation and rotation).
inline void decodeInto(const rosbag::MessageInstance& m, std::vector<std::uint8_t>& buffer,
                       tf2_msgs::TFMessage& out) {
  const std::uint32_t size = m.size();
  buffer.resize(size);
  ros::serialization::OStream write(buffer.data(), size);
  m.write(write);
  std::uint32_t count = 0;
  if (size >= 4) std::memcpy(&count, buffer.data(), 4);
  constexpr std::uint64_t kLeastTransformBytes = 4 + 8 + 4 + 4 + 24 + 32;
  if (size < 4 || std::uint64_t(count) * kLeastTransformBytes > size - 4) {
    throw ros::serialization::StreamOverrunException(
        "tf2_msgs/TFMessage: " + std::to_string(count) + " transforms cannot fit in " +
        std::to_string(size) + " bytes");
  }
  ros::serialization::IStream read(buffer.data(), size);
  ros::serialization::deserialize(read, out);
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

/// SIGINT, SIGTERM and SIGHUP set a flag instead of killing the program, so that a partial
/// output can be removed; throwIfInterrupted() turns it into a ToolError with exit code 128 +
/// the signal. A second signal removes the partial files itself and exits at once. SIGXFSZ (a
/// file-size limit reached) is ignored: the write fails with EFBIG and is reported like a full
/// disk.
void catchInterrupts();
void throwIfInterrupted();

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

// ---------------------------------------------------------------------------------------------
// Outputs: never over an input, never past a full disk
// ---------------------------------------------------------------------------------------------

/// Throws UsageError when `output` is one of `inputs` under any spelling: the same device and
/// inode when it exists (a symlink, a hard link, "./in.bag"), the same canonical path
/// otherwise; or when it is a directory, a device or a pipe (the output is renamed over its
/// name at the end, which would replace them).
void refuseOutputOverInput(const std::string& output, const std::vector<std::string>& inputs);

/// Throws ToolError when the file system that holds `output` has fewer than `bytes` available
/// (statvfs of its directory), saying how much it needs and has.
void requireFreeSpace(const std::string& output, std::uint64_t bytes);

/// An output written under a temporary name in the same directory and renamed to its own
/// name by commit(): a failed or interrupted run leaves nothing under the name, and the
/// temporary file is removed (by the destructor, or by the signal handler on a second signal).
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
  int slot_ = -1;  // in the signal handler's list of files to remove
};

/// A FILE* with a large buffer, closed by the destructor. Errors name `name`, the user's
/// output (the file written may be its temporary name).
class CsvFile {
 public:
  CsvFile(const std::string& path, const std::string& name);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  std::FILE* get() { return file_; }
  /// Throws ToolError as soon as a write has failed (a full disk stops the run at once).
  void check();
  /// Throws ToolError when anything failed to reach the disk.
  void close();

 private:
  [[noreturn]] void fail(int error);
  std::string name_;
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

  /// Writes `path`; errors name `name`, the user's output.
  BagOutput(const std::string& path, const std::string& name, Compression compression,
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
  /// Marks `topic` latched, as a latched publisher's topic is recorded; before its first write.
  void latch(const std::string& topic) { latched_.insert(topic); }
  /// Writes the last chunk and the index. A failed write (full disk) throws ToolError at once,
  /// here or in write().
  void close();

 private:
  struct Connection {
    std::string topic, datatype, md5sum, definition;
    std::vector<std::uint8_t> index;  // this chunk's (time, offset) entries, as recorded
    std::uint32_t count = 0;          // messages in this chunk
    bool latched = false;
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

  [[noreturn]] void fail(int error);

  std::string name_;
  std::FILE* file_ = nullptr;
  Compression compression_;
  std::uint32_t threshold_;
  std::uint64_t position_ = 0;  // bytes written so far
  bool chunk_open_ = false;
  std::vector<Connection> connections_;
  std::vector<std::uint8_t> chunk_;  // the open chunk's records, uncompressed
  std::vector<std::uint8_t> out_;    // what goes to the file next
  std::vector<char> compressed_;
  ros::Time chunk_start_, chunk_end_;
  std::vector<ChunkInfo> chunks_;
  std::set<std::string> latched_;
};

/// A stamp as seconds with nanosecond digits ("1700000000.005000000"), exact.
std::string formatStamp(Stamp stamp);

/// Command-line reading: the value after option `argv[i]`, or UsageError (none, or empty).
std::string optionValue(int argc, char** argv, int& i);
/// A finite number with nothing after it, or UsageError.
double parseNumber(const std::string& option, const std::string& text);
/// A finite number with |x| <= limit, or UsageError naming the limit and `why`.
double parseNumber(const std::string& option, const std::string& text, double limit,
                   const char* why);

}  // namespace tools
}  // namespace attitude_propagator
