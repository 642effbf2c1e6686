#include "aiding_summary.h"

#include <cstdint>

#include "attitude_propagator/messages/aiding_counters.h"

namespace attitude_propagator {
namespace tools {

std::string aidingCountersText(const EngineCounters& c, const std::string& prefix) {
  std::string text;
  forEachAidingCounter(c, [&](const std::string& name, std::uint64_t value) {
    if (name.compare(0, prefix.size(), prefix) != 0) return;
    text += (text.empty() ? "" : ", ") + name + " " + std::to_string(value);
  });
  return text;
}

void printAidingSummary(std::FILE* out, const EngineCounters& c, bool use_accel, bool use_mag,
                        unsigned long long accel_read, unsigned long long mag_read) {
  if (use_accel) {
    std::fprintf(out, "  accel: %llu read: %s\n", accel_read,
                 aidingCountersText(c, "accel_").c_str());
  }
  if (use_mag) {
    std::fprintf(out, "  mag: %llu read: %s\n", mag_read, aidingCountersText(c, "mag_").c_str());
  }
}

}  // namespace tools
}  // namespace attitude_propagator
