#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace attitude_propagator {
namespace tools {

Progress::Progress(std::uint64_t total, bool enabled)
    : total_(total),
      enabled_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

double Progress::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::draw(std::uint64_t done, bool force) {
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double t = std::chrono::duration<double>(now - start_).count();
  const double share = total_ > 0 ? std::min(1.0, double(done) / double(total_)) : 1.0;
  const double rate = t > 0.0 ? double(done) / t : 0.0;
  const double left = rate > 0.0 ? double(total_ - std::min(done, total_)) / rate : 0.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(share * kWidth);
  std::fprintf(stderr, "\r[%s%s] %3.0f%%  %llu/%llu msgs  %.3g msg/s  ETA %d:%02d ",
               std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(),
               100.0 * share, static_cast<unsigned long long>(done),
               static_cast<unsigned long long>(total_), rate, static_cast<int>(left) / 60,
               static_cast<int>(left) % 60);
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

}  // namespace tools
}  // namespace attitude_propagator
