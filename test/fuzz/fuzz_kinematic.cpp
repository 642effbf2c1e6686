// Fuzz target: KinematicPropagator. The input picks a configuration (any integrator name,
// including the dynamic ones the constructor must refuse, any time-policy thresholds and
// initial orientation) and then a sequence of addSample / setState / reset calls with arbitrary
// stamps and rates.
//
// Oracle after every call: the orientation is a finite unit quaternion, the rate and the stamp
// are finite, the outcome agrees with the state (a dropped or rejected sample changes nothing,
// an accepted one moves time() to its stamp), and only the constructor and setState throw, and
// only std::invalid_argument.
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "fuzz_support.h"

namespace ap = attitude_propagator;
using namespace attitude_propagator_fuzz;

namespace {

// Bounds the work per input (a burst counts every sample).
constexpr int kMaxCalls = 256;

/// A smooth, moderate rate (rad/s), so long runs of ordinary samples reach the cf4 window.
Eigen::Vector3d smoothRate(double t) {
  return {0.3 * std::sin(2.0 * t), 0.7 * std::cos(3.0 * t), -0.2};
}

void checkState(const ap::KinematicPropagator& p, const char* after) {
  requireUnit(p.orientation(), after);
  requireFinite(p.rate(), "rate", after);
  requireFinite(p.time(), "time", after);
  requireFinite(p.normError(), "normError", after);
}

void checkOutcome(const ap::KinematicPropagator& p, ap::StampOutcome outcome, double t,
                  const Eigen::Quaterniond& q_before, double t_before) {
  const bool unchanged = p.orientation().coeffs() == q_before.coeffs() && (p.time() == t_before);
  if (ap::stateHoldsAtStamp(outcome)) {
    if (p.time() != t) {
      fail("addSample", std::string(ap::outcomeName(outcome)) + " at t = " + std::to_string(t) +
                            " but time() = " + std::to_string(p.time()));
    }
  } else if (!unchanged) {
    fail("addSample", std::string(ap::outcomeName(outcome)) + " changed the state: " +
                          describe(q_before) + " -> " + describe(p.orientation()));
  }
}

ap::StampOutcome addSample(ap::KinematicPropagator& p, double t, const Eigen::Vector3d& w) {
  const Eigen::Quaterniond q_before = p.orientation();
  const double t_before = p.time();
  const ap::StampOutcome outcome = noThrow("addSample", [&] { return p.addSample(t, w); });
  FUZZ_TRACE("addSample(%.17g, %s) -> %s", t, describe(w).c_str(), ap::outcomeName(outcome));
  checkState(p, "addSample");
  checkOutcome(p, outcome, t, q_before, t_before);
  return outcome;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);

  ap::KinematicConfig config;
  config.integrator = ap::integratorFromName(readIntegratorCode(in, integratorCodes()));
  if (in.flag()) config.time_policy.max_dt = in.value();
  if (in.flag()) config.time_policy.backward_jump = in.value();
  if (in.flag()) config.initial_q_WB = in.quaternion();
  const double epoch = in.flag() ? 1.7e9 : 0.0;

  FUZZ_TRACE("KinematicPropagator: integrator %s, max_dt %.17g, backward_jump %.17g, %s",
             ap::integratorName(config.integrator).c_str(), config.time_policy.max_dt,
             config.time_policy.backward_jump, describe(config.initial_q_WB).c_str());
  std::optional<ap::KinematicPropagator> p;
  if (!acceptedBy("KinematicPropagator(config)", [&] { p.emplace(config); })) return 0;
  checkState(*p, "construction");

  for (int calls = 0; calls < kMaxCalls && !in.exhausted(); ++calls) {
    const double last = p->anchored() ? p->time() : epoch;
    switch (in.choice(8)) {
      case 5: {  // a burst of evenly spaced smooth samples
        static const double kPeriods[] = {1e-3, 5e-3, 1e-2, 0.25};
        const double h = kPeriods[in.choice(4)];
        const int n = 1 + static_cast<int>(in.choice(32));
        for (int k = 1; k <= n && calls < kMaxCalls; ++k, ++calls) {
          addSample(*p, last + k * h, smoothRate(last + k * h));
        }
        break;
      }
      case 6: {
        const double t = in.stamp(last);
        const Eigen::Quaterniond q = in.quaternion();
        const Eigen::Vector3d w = in.vector3();
        const Eigen::Quaterniond q_before = p->orientation();
        const double t_before = p->time();
        FUZZ_TRACE("setState(%.17g, %s, %s)", t, describe(q).c_str(), describe(w).c_str());
        if (acceptedBy("setState", [&] { p->setState(t, q, w); })) {
          if (p->time() != t) fail("setState", "time() is not the stamp given");
        } else if (p->orientation().coeffs() != q_before.coeffs() || p->time() != t_before) {
          fail("setState", "a refused state changed the propagator");
        }
        checkState(*p, "setState");
        break;
      }
      case 7:
        FUZZ_TRACE("reset()");
        noThrow("reset", [&] { p->reset(); });
        checkState(*p, "reset");
        if (p->anchored()) fail("reset", "still anchored");
        break;
      default: {
        const double t = in.stamp(last);
        const Eigen::Vector3d w = in.flag() ? in.vector3() : smoothRate(t);
        addSample(*p, t, w);
        break;
      }
    }
  }
  return 0;
}
