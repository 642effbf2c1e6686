// Text taken from a message or a parameter (a frame id, a type name, a publisher's name, a
// parameter's value) on its way into a log line or a tool's message. Such text is the sender's
// choice: a 10 MB frame id would otherwise be written in full to every console, /rosout and log
// file, once per warning, and a newline in it could fake a line of its own. One rule for the
// node, the bag tools and the parameters' errors.
#pragma once

#include <cstddef>
#include <string>

namespace attitude_propagator {

/// Longest text from a message that is logged as it is (bytes). A tf frame id or a message
/// type name is a few tens of bytes; 64 keeps every real one whole.
constexpr std::size_t kLogTextBytes = 64;

/// `text` for a log line: control characters (below 0x20, and DEL) replaced by '?', and
/// when longer than max_bytes, its first max_bytes (shortened to the last whole UTF-8
/// character) followed by "...(N bytes)", N the length of the whole text. The marker is
/// ASCII: rosconsole under the C locale turns every byte above 0x7F into '?'. max_bytes is
/// raised for text that quotes message strings inside a longer explanation (tf's errors).
std::string logText(const std::string& text, std::size_t max_bytes = kLogTextBytes);

/// The publishers of two timelines taking turns on a clock topic (ClockTimeline), for the
/// node's warning and diagnostics and propagate_bag's summary: `followed` (the later
/// timeline's), `other` (empty, or the same: one publisher alternating), each through logText.
std::string clockPublishersText(const std::string& followed, const std::string& other);

}  // namespace attitude_propagator
