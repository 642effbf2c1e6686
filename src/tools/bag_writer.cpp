#include "bag_writer.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <roslz4/lz4s.h>

#include "bag_format.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

// ---------------------------------------------------------------------------------------------
// Bag output (format 2.0: records of "<header length><header><data length><data>", the header
// a list of "<field length>name=value"; integers little-endian, times as sec then nsec)
// ---------------------------------------------------------------------------------------------

namespace {

using namespace bag_format;  // NOLINT: the format's names are this file's vocabulary
constexpr std::uint32_t kIndexVersion = 1;
constexpr std::size_t kBagHeaderLength = 4096;  // header and padding, as rosbag writes it
constexpr int kLz4BlockSizeId = 6;              // rosbag's

void appendBytes(std::vector<std::uint8_t>& out, const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  out.insert(out.end(), p, p + size);
}

template <class T>
void appendValue(std::vector<std::uint8_t>& out, const T& value) {
  appendBytes(out, &value, sizeof value);  // the format's little-endian is the host's (x86, ARM)
}

void appendTime(std::vector<std::uint8_t>& out, const ros::Time& t) {
  appendValue(out, t.sec);
  appendValue(out, t.nsec);
}

/// A record header under construction.
class Fields {
 public:
  template <class T>
  Fields& add(const char* name, const T& value) {
    return addRaw(name, &value, sizeof value);
  }
  Fields& add(const char* name, const ros::Time& t) {
    std::vector<std::uint8_t> v;
    appendTime(v, t);
    return addRaw(name, v.data(), v.size());
  }
  Fields& add(const char* name, const std::string& value) {
    return addRaw(name, value.data(), value.size());
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  Fields& addRaw(const char* name, const void* value, std::size_t size) {
    const std::size_t n = std::strlen(name);
    appendValue(bytes_, static_cast<std::uint32_t>(n + 1 + size));
    appendBytes(bytes_, name, n);
    bytes_.push_back('=');
    appendBytes(bytes_, value, size);
    return *this;
  }
  std::vector<std::uint8_t> bytes_;
};

void appendRecord(std::vector<std::uint8_t>& out, const Fields& header, const void* data,
                  std::size_t size) {
  appendValue(out, static_cast<std::uint32_t>(header.bytes().size()));
  appendBytes(out, header.bytes().data(), header.bytes().size());
  appendValue(out, static_cast<std::uint32_t>(size));
  appendBytes(out, data, size);
}

/// A connection record: topic and id in the header, the connection header as data.
void appendConnection(std::vector<std::uint8_t>& out, std::uint32_t id, const std::string& topic,
                      const std::string& datatype, const std::string& md5sum,
                      const std::string& definition, bool latched) {
  Fields data;
  data.add("topic", topic).add("type", datatype).add("md5sum", md5sum);
  data.add("message_definition", definition);
  // As `rosbag record` stores a latched publisher's connection header: `rosbag play` then
  // latches the topic, so a node that subscribes later still receives it.
  if (latched)
    data.add("callerid", std::string("/propagate_bag")).add("latching", std::string("1"));
  appendRecord(out, Fields().add("op", Op::kConnection).add("conn", id).add("topic", topic),
               data.bytes().data(), data.bytes().size());
}

}  // namespace

BagOutput::BagOutput(const std::string& path, const std::string& name, Compression compression,
                     std::uint32_t chunk_threshold)
    : name_(name), compression_(compression), threshold_(chunk_threshold) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw ToolError(name + ": cannot write (" + std::strerror(errno) + ")");
  out_.assign(kVersionLine, kVersionLine + kVersionLength);
  put(out_);
  writeHeader(0);  // rewritten by close()
  chunk_.reserve(threshold_ + (64u << 10));
}

BagOutput::~BagOutput() {
  if (file_) std::fclose(file_);
}

std::uint32_t BagOutput::connection(const std::string& topic, const char* datatype,
                                    const char* md5sum, const char* definition) {
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    if (connections_[id].topic == topic) return id;
  }
  const auto id = static_cast<std::uint32_t>(connections_.size());
  connections_.push_back({topic, datatype, md5sum, definition, {}, 0, false});
  // Also inside the chunk where it first appears, as rosbag writes it (`rosbag reindex` needs it);
  // the message that follows opens the chunk.
  connections_.back().latched = latched_.count(topic) > 0;
  appendConnection(chunk_, id, topic, datatype, md5sum, definition, connections_.back().latched);
  return id;
}

std::uint8_t* BagOutput::beginMessage(std::uint32_t id, const ros::Time& time,
                                      std::uint32_t length) {
  if (time < ros::TIME_MIN) {
    throw ToolError(name_ + ": record time " + std::to_string(time.toSec()) +
                    " is before ros::TIME_MIN");
  }
  if (!chunk_open_) {
    chunk_open_ = true;
    chunk_start_ = chunk_end_ = time;
  }
  chunk_start_ = std::min(chunk_start_, time);
  chunk_end_ = std::max(chunk_end_, time);
  Connection& c = connections_[id];
  appendTime(c.index, time);
  appendValue(c.index, static_cast<std::uint32_t>(chunk_.size()));
  ++c.count;
  const Fields header = Fields().add("op", Op::kMessage).add("conn", id).add("time", time);
  appendValue(chunk_, static_cast<std::uint32_t>(header.bytes().size()));
  appendBytes(chunk_, header.bytes().data(), header.bytes().size());
  appendValue(chunk_, length);
  chunk_.resize(chunk_.size() + length);
  return chunk_.data() + chunk_.size() - length;
}

void BagOutput::writeChunk() {
  if (!chunk_open_) return;
  ChunkInfo info{position_, chunk_start_, chunk_end_, {}};
  const auto size = static_cast<std::uint32_t>(chunk_.size());
  const void* data = chunk_.data();
  std::uint32_t stored = size;
  if (compression_ == Compression::Lz4) {
    // The frame roslz4 writes for rosbag; the bound is LZ4's worst case plus the framing.
    compressed_.resize(size + size / 255 + 16 * (size / 65536 + 1) + 64);
    unsigned int n = static_cast<unsigned int>(compressed_.size());
    if (roslz4_buffToBuffCompress(reinterpret_cast<char*>(chunk_.data()), size, compressed_.data(),
                                  &n, kLz4BlockSizeId) != ROSLZ4_OK) {
      throw ToolError(name_ + ": LZ4 compression failed");
    }
    data = compressed_.data();
    stored = n;
  }
  out_.clear();
  appendRecord(
      out_,
      Fields()
          .add("op", Op::kChunk)
          .add("compression", std::string(compression_ == Compression::Lz4 ? "lz4" : "none"))
          .add("size", size),
      data, stored);
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    Connection& c = connections_[id];
    if (c.count == 0) continue;
    appendRecord(out_,
                 Fields()
                     .add("op", Op::kIndex)
                     .add("ver", kIndexVersion)
                     .add("conn", id)
                     .add("count", c.count),
                 c.index.data(), c.index.size());
    info.counts.emplace_back(id, c.count);
    c.index.clear();
    c.count = 0;
  }
  put(out_);
  chunks_.push_back(std::move(info));
  chunk_.clear();
  chunk_open_ = false;
}

void BagOutput::writeHeader(std::uint64_t index_position) {
  const Fields header = Fields()
                            .add("op", Op::kBagHeader)
                            .add("index_pos", index_position)
                            .add("conn_count", static_cast<std::uint32_t>(connections_.size()))
                            .add("chunk_count", static_cast<std::uint32_t>(chunks_.size()));
  // Padded as rosbag pads it (readers such as `rosbag reindex` skip exactly this much).
  const std::size_t padding = kBagHeaderLength - header.bytes().size();
  out_.clear();
  appendRecord(out_, header, std::string(padding, ' ').data(), padding);
  put(out_);
}

void BagOutput::fail(int error) {
  throw ToolError(name_ + ": write failed (" + std::strerror(error) + ")");
}

void BagOutput::put(const std::vector<std::uint8_t>& bytes) {
  // Stops at the first failed write: a full disk ends the run now, not after the whole bag.
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) fail(errno);
  position_ += bytes.size();
}

void BagOutput::close() {
  writeChunk();
  const std::uint64_t index_position = position_;
  out_.clear();
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    const Connection& c = connections_[id];
    appendConnection(out_, id, c.topic, c.datatype, c.md5sum, c.definition, c.latched);
  }
  for (const ChunkInfo& info : chunks_) {
    std::vector<std::uint8_t> counts;
    for (const auto& [id, n] : info.counts) {
      appendValue(counts, id);
      appendValue(counts, n);
    }
    appendRecord(out_,
                 Fields()
                     .add("op", Op::kChunkInfo)
                     .add("ver", kIndexVersion)
                     .add("chunk_pos", info.position)
                     .add("start_time", info.start)
                     .add("end_time", info.end)
                     .add("count", static_cast<std::uint32_t>(info.counts.size())),
                 counts.data(), counts.size());
  }
  put(out_);
  if (std::fseek(file_, kVersionLength, SEEK_SET) != 0) fail(errno);
  writeHeader(index_position);
  const int closed = std::fclose(file_);
  const int error = errno;
  file_ = nullptr;
  if (closed != 0) fail(error);
}

}  // namespace tools
}  // namespace attitude_propagator
