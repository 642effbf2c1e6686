#include "bag_check.h"

#include <bzlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <roslz4/lz4s.h>

#include "attitude_propagator/quoted_text.h"
#include "bag_format.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

namespace {

using namespace bag_format;  // NOLINT: the format's names are this file's vocabulary
// Limits that keep a damaged length from asking for an absurd amount of memory. rosbag closes
// a chunk once it passes its threshold (768 KiB unless the recorder was told otherwise), so a
// chunk is that plus one message; record headers hold a few short fields.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t(1) << 30;
constexpr std::uint32_t kMaxHeaderBytes = 1u << 20;

/// A structural fault, with where it is.
struct Fault : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string at(std::uint64_t position) { return " at byte " + std::to_string(position); }

using Fields = std::map<std::string, std::string>;

/// Parses "<length>name=value" fields filling exactly `size` bytes; false when malformed.
bool parseFields(const std::uint8_t* data, std::uint64_t size, Fields& fields) {
  fields.clear();
  std::uint64_t i = 0;
  while (i < size) {
    if (size - i < 4) return false;
    std::uint32_t length;
    std::memcpy(&length, data + i, 4);
    i += 4;
    if (length > size - i) return false;
    const char* field = reinterpret_cast<const char*>(data + i);
    const char* equals = static_cast<const char*>(std::memchr(field, '=', length));
    if (!equals) return false;
    fields[std::string(field, equals)] = std::string(equals + 1, field + length);
    i += length;
  }
  return true;
}

template <class T>
T value(const Fields& fields, const char* name, const std::string& where) {
  const auto it = fields.find(name);
  if (it == fields.end() || it->second.size() != sizeof(T)) {
    throw Fault(std::string("no valid '") + name + "' field" + where);
  }
  T out;
  std::memcpy(&out, it->second.data(), sizeof out);
  return out;
}

/// One record: its header fields and where its data lies.
struct Record {
  Fields fields;
  std::uint8_t op = 0;
  std::uint64_t data = 0;  ///< position of the data
  std::uint32_t data_length = 0;
  std::uint64_t end = 0;  ///< position after the record
};

/// Reads the records of a byte range (the file, or a decompressed chunk), every read bounded
/// by the range.
class Bytes {
 public:
  virtual ~Bytes() = default;
  virtual std::uint64_t size() const = 0;
  /// Copies [position, position + n) into out; the range is checked by the caller.
  virtual void copy(std::uint64_t position, std::size_t n, void* out) = 0;

  Record record(std::uint64_t position, const char* what) {
    const std::string where = " in the " + std::string(what) + at(position);
    Record r;
    if (position > size() || size() - position < 8) throw Fault("record cut short" + where);
    std::uint32_t header_length;
    copy(position, 4, &header_length);
    if (header_length > kMaxHeaderBytes || header_length > size() - position - 8) {
      throw Fault("record header length " + std::to_string(header_length) + " out of bounds" +
                  where);
    }
    std::vector<std::uint8_t> header(header_length);
    copy(position + 4, header_length, header.data());
    if (!parseFields(header.data(), header_length, r.fields)) {
      throw Fault("malformed record header" + where);
    }
    r.op = value<std::uint8_t>(r.fields, "op", where);
    r.data = position + 4 + header_length + 4;
    copy(r.data - 4, 4, &r.data_length);
    if (r.data_length > size() - r.data) {
      throw Fault("record data length " + std::to_string(r.data_length) + " out of bounds" + where);
    }
    r.end = r.data + r.data_length;
    return r;
  }

  /// A record of the given kind, or Fault.
  Record record(std::uint64_t position, Op op, const char* what) {
    Record r = record(position, what);
    if (r.op != op) {
      throw Fault("expected a " + std::string(what) + " record, found op " + std::to_string(r.op) +
                  at(position));
    }
    return r;
  }

  /// The data of a record whose header fields are themselves fields (a connection record).
  void requireFields(const Record& r, const char* what) {
    std::vector<std::uint8_t> data(r.data_length);
    copy(r.data, r.data_length, data.data());
    Fields fields;
    if (!parseFields(data.data(), data.size(), fields)) {
      throw Fault("malformed " + std::string(what) + " data" + at(r.data));
    }
  }
};

class FileBytes : public Bytes {
 public:
  explicit FileBytes(const std::string& path) : in_(path, std::ios::binary) {
    in_.seekg(0, std::ios::end);
    size_ = in_ ? static_cast<std::uint64_t>(in_.tellg()) : 0;
  }
  bool good() const { return static_cast<bool>(in_); }
  std::uint64_t size() const override { return size_; }
  void copy(std::uint64_t position, std::size_t n, void* out) override {
    in_.seekg(static_cast<std::streamoff>(position));
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!in_) throw Fault("read failed" + at(position));
  }

 private:
  std::ifstream in_;
  std::uint64_t size_ = 0;
};

class BufferBytes : public Bytes {
 public:
  BufferBytes(const std::uint8_t* data, std::uint64_t size) : data_(data), size_(size) {}
  std::uint64_t size() const override { return size_; }
  void copy(std::uint64_t position, std::size_t n, void* out) override {
    std::memcpy(out, data_ + position, n);
  }

 private:
  const std::uint8_t* data_;
  std::uint64_t size_;
};

struct ChunkInfo {
  std::uint64_t position;
  std::uint32_t connections;  // index records after the chunk
};

/// The chunk's records, decompressed and walked; every index entry must point at a message.
void checkChunk(FileBytes& file, const ChunkInfo& info, const std::set<std::uint32_t>& known,
                std::uint64_t& messages) {
  const Record chunk = file.record(info.position, kChunk, "chunk");
  const auto compression_it = chunk.fields.find("compression");
  if (compression_it == chunk.fields.end()) throw Fault("chunk without a compression field");
  const std::string& compression = compression_it->second;
  const auto size = value<std::uint32_t>(chunk.fields, "size", " in the chunk header");
  if (size > kMaxChunkBytes || chunk.data_length > kMaxChunkBytes) {
    throw Fault("chunk of " + std::to_string(size) + " bytes, more than a chunk can be");
  }

  // The index records that follow the chunk, read first: they say how many messages it holds.
  std::vector<std::uint32_t> offsets;
  std::uint64_t next = chunk.end;
  std::uint64_t in_chunk = 0;
  for (std::uint32_t i = 0; i < info.connections; ++i) {
    const Record index = file.record(next, kIndex, "index");
    const auto count = value<std::uint32_t>(index.fields, "count", " in an index record");
    const auto connection = value<std::uint32_t>(index.fields, "conn", " in an index record");
    if (value<std::uint32_t>(index.fields, "ver", " in an index record") != 1 ||
        index.data_length != std::uint64_t(count) * 12 || !known.count(connection)) {
      throw Fault("inconsistent index record" + at(next));
    }
    std::vector<std::uint8_t> entries(index.data_length);
    file.copy(index.data, entries.size(), entries.data());
    for (std::uint32_t k = 0; k < count; ++k) {
      std::uint32_t offset;
      std::memcpy(&offset, entries.data() + 12 * k + 8, 4);  // after the time (sec, nsec)
      offsets.push_back(offset);
    }
    in_chunk += count;
    next = index.end;
  }

  std::vector<std::uint8_t> stored(chunk.data_length);
  file.copy(chunk.data, stored.size(), stored.data());
  std::unique_ptr<std::uint8_t[]> decompressed;
  const std::uint8_t* data = stored.data();
  if (compression == "none") {
    if (size != chunk.data_length) throw Fault("chunk size differs from its stored length");
  } else if (compression == "bz2" || compression == "lz4") {
    decompressed.reset(new std::uint8_t[std::max<std::uint32_t>(size, 1)]);
    unsigned int produced = size;
    char* in = reinterpret_cast<char*>(stored.data());
    char* out = reinterpret_cast<char*>(decompressed.get());
    const auto in_size = static_cast<unsigned int>(stored.size());
    const bool ok = compression == "bz2"
                        ? BZ2_bzBuffToBuffDecompress(out, &produced, in, in_size, 0, 0) == BZ_OK
                        : roslz4_buffToBuffDecompress(in, in_size, out, &produced) == ROSLZ4_OK;
    if (!ok) throw Fault(compression + " data do not decompress (corrupted)");
    if (produced != size) {
      throw Fault(compression + " data decompress to " + std::to_string(produced) +
                  " bytes, not the " + std::to_string(size) + " its header says");
    }
    data = decompressed.get();
  } else {
    throw Fault("unknown compression '" + compression + "'");
  }

  // Walk the records; keep the messages' positions.
  BufferBytes bytes(data, size);
  std::vector<std::uint32_t> starts;
  for (std::uint64_t position = 0; position < size;) {
    const Record r = bytes.record(position, "chunk's data");
    if (r.op == kMessage) {
      const auto connection = value<std::uint32_t>(r.fields, "conn", " in a message record");
      if (!known.count(connection)) throw Fault("message of an unknown connection in the chunk");
      starts.push_back(static_cast<std::uint32_t>(position));
    } else if (r.op == kConnection) {
      bytes.requireFields(r, "connection record's");
    } else {
      throw Fault("unexpected op " + std::to_string(r.op) + " in the chunk's data");
    }
    position = r.end;
  }
  for (std::uint32_t offset : offsets) {
    if (!std::binary_search(starts.begin(), starts.end(), offset)) {
      throw Fault("an index entry points at byte " + std::to_string(offset) +
                  " of the chunk, where no message starts");
    }
  }
  messages += in_chunk;
}

/// A bag of another format version (#ROSBAG V1.2, a ROS 1 bag older than 2010): refused by its
/// version, not as damaged. Its first line is "#ROSBAG V<version>\n".
void refuseOtherVersion(const std::string& path, FileBytes& file) {
  const std::string magic = "#ROSBAG V";
  std::string line(static_cast<std::size_t>(std::min<std::uint64_t>(file.size(), 32)), '\0');
  try {
    file.copy(0, line.size(), &line[0]);
  } catch (const Fault&) {
    return;
  }
  if (line.compare(0, magic.size(), magic) != 0) return;
  const std::string version = line.substr(magic.size(), line.find('\n') - magic.size());
  throw ToolError(path + ": a bag of format version " + logText(version) +
                  "; accepted: version 2.0 (the Python rosbag reads the old format: `rosbag "
                  "filter " +
                  path + " new.bag True` writes it as 2.0)");
}

}  // namespace

void checkBagStructure(const std::string& path) {
  FileBytes file(path);
  if (!file.good() || file.size() < kVersionLength) return;  // rosbag says what is wrong
  char version[kVersionLength];
  try {
    file.copy(0, kVersionLength, version);
  } catch (const Fault&) {
    return;
  }
  if (std::memcmp(version, kVersionLine, kVersionLength) != 0) {
    refuseOtherVersion(path, file);
    return;  // not a bag at all: rosbag says so
  }

  std::uint64_t messages = 0;
  std::size_t chunk_number = 0;
  std::vector<ChunkInfo> chunks;
  try {
    const Record header = file.record(kVersionLength, kBagHeader, "bag header");
    const auto encryptor = header.fields.find("encryptor");
    if (encryptor != header.fields.end() && !encryptor->second.empty()) return;
    const auto index = value<std::uint64_t>(header.fields, "index_pos", " in the bag header");
    if (index == 0) return;  // unindexed: rosbag says so, and how to reindex
    if (index >= file.size()) {
      throw Fault("its index" + at(index) + " lies past the end of the file (" +
                  std::to_string(file.size()) +
                  " bytes); `rosbag reindex` may recover a truncated recording");
    }
    const auto connection_count =
        value<std::uint32_t>(header.fields, "conn_count", " in the bag header");
    const auto chunk_count =
        value<std::uint32_t>(header.fields, "chunk_count", " in the bag header");
    std::set<std::uint32_t> known;
    std::uint64_t next = index;
    for (std::uint32_t i = 0; i < connection_count; ++i) {
      const Record c = file.record(next, kConnection, "connection");
      known.insert(value<std::uint32_t>(c.fields, "conn", " in a connection record"));
      file.requireFields(c, "connection record's");
      next = c.end;
    }
    for (std::uint32_t i = 0; i < chunk_count; ++i) {
      const Record c = file.record(next, kChunkInfo, "chunk info");
      const auto count = value<std::uint32_t>(c.fields, "count", " in a chunk info record");
      const auto position = value<std::uint64_t>(c.fields, "chunk_pos", " in a chunk info record");
      if (c.data_length != std::uint64_t(count) * 8 || position >= index) {
        throw Fault("inconsistent chunk info record" + at(next));
      }
      chunks.push_back({position, count});
      next = c.end;
    }
    std::sort(chunks.begin(), chunks.end(),
              [](const ChunkInfo& a, const ChunkInfo& b) { return a.position < b.position; });
    for (const ChunkInfo& chunk : chunks) {
      ++chunk_number;
      checkChunk(file, chunk, known, messages);
    }
  } catch (const Fault& fault) {
    if (chunk_number == 0) {
      throw ToolError(path + ": damaged or truncated bag: " + fault.what());
    }
    throw ToolError(path + ": damaged after " + std::to_string(messages) + " messages (chunk " +
                    std::to_string(chunk_number) + " of " + std::to_string(chunks.size()) +
                    at(chunks[chunk_number - 1].position) + "): " + fault.what());
  }
}

}  // namespace tools
}  // namespace attitude_propagator
