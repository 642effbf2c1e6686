#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

std::string logText(const std::string& text, std::size_t max_bytes) {
  std::size_t keep = text.size();
  if (keep > max_bytes) {
    keep = max_bytes;
    // Never end inside a UTF-8 character: back off over continuation bytes (10xxxxxx) to the
    // start of the character that did not fit.
    while (keep > 0 && (static_cast<unsigned char>(text[keep]) & 0xC0) == 0x80) --keep;
  }
  std::string out = text.substr(0, keep);
  for (char& c : out) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7F) c = '?';
  }
  if (keep < text.size()) out += "...(" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string clockPublishersText(const std::string& followed, const std::string& other) {
  if (other.empty() || other == followed) return "one publisher alternating: " + logText(followed);
  return "followed: " + logText(followed) + ", other: " + logText(other);
}

}  // namespace attitude_propagator
