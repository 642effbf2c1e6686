// A check of a bag file's structure before rosbag reads it.
//
// rosbag's reader trusts the lengths and offsets stored in the file: a message's header length
// is read from the decompressed chunk and parsed without a bounds check, an index offset is
// used as a position in the chunk without one, and bz2 output shorter than the chunk's declared
// size is not noticed. A few bytes overwritten in a chunk or its index therefore make it read
// past its buffers (SIGSEGV) rather than throw. Catching exceptions cannot help there, so the
// tools check the structure first, with every read bounded: the records of the index section,
// each chunk decompressed (bz2's and roslz4's checksums catch damaged compressed data) and
// walked record by record, and every index entry pointing at a message record inside its chunk.
// A bag that passes can only hold wrong values in message fields, which deserialisation either
// takes or rejects with an exception.
#pragma once

#include <string>

namespace attitude_propagator {
namespace tools {

/// Checks the bag at `path` (format 2.0) and throws ToolError naming the file, the damaged part
/// and how many messages the chunks before it hold ("damaged after N messages"). Memory: one
/// chunk, stored and decompressed; time: one pass over the file. Bags this check cannot read
/// (format 1.2, encrypted chunks, an index not written yet) are left to rosbag, which reports
/// them.
void checkBagStructure(const std::string& path);

}  // namespace tools
}  // namespace attitude_propagator
