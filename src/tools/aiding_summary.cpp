#include "aiding_summary.h"

#include <cstdint>
#include <optional>

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

void printFieldFit(std::FILE* out, const HardIronFit& fit) {
  const std::optional<HardIronSphere> sphere = fit.solve();
  if (!sphere) {
    std::fprintf(out,
                 "  mag_bias from the reads: none (%llu reads fix no sphere: fewer than 5, or "
                 "all on one circle)\n",
                 static_cast<unsigned long long>(fit.count()));
    return;
  }
  const Eigen::Vector3d& c = sphere->centre;
  const Eigen::Vector3d& s = sphere->centre_stddev;
  std::fprintf(out,
               "  mag_bias from the reads: [%.3g, %.3g, %.3g] T, stddev [%.2g, %.2g, %.2g] T; "
               "field %.3g T, the reads %.2g T off it (rms), spread at least %.2g T: ",
               c.x(), c.y(), c.z(), s.x(), s.y(), s.z(), sphere->radius, sphere->off_rms,
               sphere->least_spread);
  if (sphere->determined()) {
    std::fprintf(out, "determined (give it as mag_bias)\n");
  } else {
    std::fprintf(out,
                 "not determined (each axis' stddev at most %g T and a spread %g times the "
                 "reads' scatter needed: turn the sensor every way)\n",
                 kHardIronDetermined, kHardIronSpread);
  }
}

}  // namespace tools
}  // namespace attitude_propagator
