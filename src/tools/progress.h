// The progress line a long run draws on a terminal.
#pragma once

#include <chrono>
#include <cstdint>

namespace attitude_propagator {
namespace tools {

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

}  // namespace tools
}  // namespace attitude_propagator
