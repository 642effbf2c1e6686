// BagOutput: our own writer of the bag format 2.0, for propagate_bag's output bag.
//
// Why hand-written: rosbag::Bag::write seeks to the end of the file twice per message, which with
// glibc's read-write FILE costs an fstat, an lseek and a 4 KiB read each, plus one write per
// message uncompressed: about six system calls per message, against about two per chunk here.
// Measured with bench/bag_writer.cpp, the two writers alternating (`bash scripts/build.sh
// bench_bag_writer && .workspace/devel/lib/attitude_propagator/bench_bag_writer 5 400000 /tmp`:
// 400 k sensor_msgs/Imu, uncompressed, medians of 5 rounds each; docs/benchmarks.md, "Writing
// bags"): rosbag::Bag::write took 6.6-7.7 s wall and 5.4-5.5 s CPU (3.2-3.3 s of it in the
// kernel), this writer 0.17 s wall and 0.13 s CPU, about 40× less either way, on two shared
// cores of a virtual machine under a load of about 3. The absolute times depend on what a
// system call costs where it runs; rosbag's user time alone (2.2 s) is still about 20 times this
// writer's (0.11 s). Within propagate_bag as a whole, rosbag's writer held it at 285× real time
// (docs/bag_tools.md, Throughput). The file is laid out as rosbag::Bag lays it out (the same
// records, header padding and chunk threshold), so rosbag's readers, `rosbag check`,
// `rosbag info` and `rosbag reindex` take it as their own
// (test/bag/test_bag_writer.cpp runs them on it).
//
// The layout written (names and op codes in bag_format.h). Every record is
// "<u32 header length><header><u32 data length><data>"; a header is a list of fields
// "<u32 field length>name=value"; integers are little-endian, a time is u32 sec then u32 nsec.
//
//   "#ROSBAG V2.0\n"
//   bag header    op=0x03, index_pos (u64: where the connection records at the end start),
//                 conn_count (u32), chunk_count (u32); data: spaces, so that header and data
//                 take 4096 bytes (the two lengths not counted), as rosbag pads it. Written
//                 with zeros first and rewritten in place by close(), when the three values
//                 are known.
//   then per chunk, in order:
//     chunk       op=0x05, compression ("none" or "lz4": roslz4's frame, block size id 6, as
//                 rosbag writes it), size (u32, the records' size uncompressed); data: the
//                 chunk's records, compressed or not:
//                   connection  op=0x07, conn (u32 id), topic; data: the connection header as
//                               fields topic, type, md5sum, message_definition, and for a topic
//                               marked latched callerid=/propagate_bag and latching=1 (as
//                               `rosbag record` stores a latched publisher). Only in the chunk
//                               where the connection's first message is (`rosbag reindex`
//                               needs it there).
//                   message     op=0x02, conn (u32), time (the record time); data: the message
//                               serialised.
//                 A chunk is closed when its records pass 768 KiB uncompressed (rosbag's
//                 default threshold), and by close().
//     index data  op=0x04, ver=1 (u32), conn (u32), count (u32); data: count entries of
//                 (time, u32 offset of the message record in the uncompressed chunk), as
//                 recorded. One per connection with messages in the chunk, by connection id.
//   then the index section, at index_pos:
//     connection  each connection once more, by id, as above.
//     chunk info  op=0x06, ver=1 (u32), chunk_pos (u64: the chunk record's position),
//                 start_time, end_time (the chunk's earliest and latest record times), count
//                 (u32: connections in the chunk); data: count pairs (u32 conn, u32 messages).
//
// Memory: one chunk and its index, and a few bytes per chunk. A failed write (a full disk) throws
// ToolError at once, from write() or close().
#pragma once

#include <cstdint>
#include <cstdio>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <ros/serialization.h>
#include <ros/time.h>

namespace attitude_propagator {
namespace tools {

/// A bag (format 2.0) written a chunk at a time. Messages are serialised into an in-memory chunk
/// that goes to the file in one write when it passes the threshold (LZ4-compressed with
/// rosbag's own roslz4 if asked), followed by its index records; the connections and the chunk
/// list close the file (the layout above).
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

}  // namespace tools
}  // namespace attitude_propagator
