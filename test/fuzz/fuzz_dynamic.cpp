// Fuzz target: DynamicPropagator. The input picks a configuration (inertia as principal moments
// or a full tensor with off-diagonal terms, any integrator name, torque_input on or off,
// max_step, tolerance, torque timeout, time-policy thresholds, initial state) and then a
// sequence of advanceTo / setTorque / setRate / setState / reset calls.
//
// Oracle after every call: the orientation is a finite unit quaternion, the rate, kinetic
// energy, angular momentum and stamp are finite, a dropped or rejected input changes nothing,
// an accepted one leaves the state at its stamp (or at the current time for a late input), and
// only the constructor and setState throw, and only std::invalid_argument. setTorque with the
// exact model gets a zero torque only: a non-zero one is a documented std::logic_error.
#include <algorithm>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "fuzz_support.h"

namespace ap = attitude_propagator;
using namespace attitude_propagator_fuzz;

namespace {

// Bounded time per input: at most kMaxCalls calls, and a stamp ahead of the propagator is
// clamped to at most min(10 s, kMaxGridSteps * max_step) beyond time(), so one call commits at
// most kMaxGridSteps grid steps whatever max_step and max_dt are. The core's own bound on the
// work of one call (huge horizons on a fine grid) is exercised by the parameter target, which
// drives validated configurations on the node's clock without this clamp.
constexpr int kMaxCalls = 64;
constexpr double kMaxHorizon = 10.0;
constexpr double kMaxGridSteps = 1000.0;

ap::RigidBody makeBody(ByteReader& in) {
  switch (in.choice(4)) {
    case 0: {  // ordinary bodies: sphere, triaxial, symmetric top, a tensor with products
      static const std::vector<std::vector<double>> kBodies = {
          {1, 1, 1}, {1, 2, 3}, {1, 1, 0.5}, {2, 3, 4, 0.1, -0.2, 0.3}, {1, 2, 2.5, 0, 0, 0.5}};
      std::vector<double> v = kBodies[in.choice(kBodies.size())];
      const double scale = in.flag() ? in.value() : 1.0;
      for (double& x : v) x *= scale;
      return ap::RigidBody::fromParameter(v);
    }
    case 1: {  // three arbitrary moments, the triangle inequality waived or required
      const Eigen::Vector3d m = in.vector3();
      return ap::RigidBody::fromPrincipalMoments(
          m, in.flag() ? ap::RigidBody::TriangleInequality::Ignore
                       : ap::RigidBody::TriangleInequality::Require);
    }
    case 2: {  // six arbitrary tensor elements
      std::vector<double> v(6);
      for (double& x : v) x = in.value();
      return ap::RigidBody::fromParameter(v);
    }
    default: {  // a diagonal tensor with small products of inertia
      std::vector<double> v{in.value(), in.value(), in.value()};
      for (int i = 0; i < 3; ++i) v.push_back(v[i] * 1e-3 * (in.byte() - 128));
      return ap::RigidBody::fromParameter(v);
    }
  }
}

double stepValue(ByteReader& in) {
  static const double kSteps[] = {1e-3, 5e-3, 1e-2, 0.1, 1.0};
  return in.flag() ? kSteps[in.choice(5)] : in.value();
}

void checkState(const ap::DynamicPropagator& p, const char* after) {
  requireUnit(p.state().q_WB, after);
  requireFinite(p.state().w_B, "rate", after);
  requireFinite(p.kineticEnergy(), "kineticEnergy", after);
  requireFinite(p.angularMomentum_B(), "angularMomentum_B", after);
  requireFinite(p.time(), "time", after);
  requireFinite(p.normError(), "normError", after);
}

struct Snapshot {
  Eigen::Quaterniond q;
  Eigen::Vector3d w;
  double t;
  explicit Snapshot(const ap::DynamicPropagator& p)
      : q(p.state().q_WB), w(p.state().w_B), t(p.time()) {}
  bool operator==(const Snapshot& o) const {
    return q.coeffs() == o.q.coeffs() && w == o.w && t == o.t;
  }
};

/// A stamped input either leaves the state at its stamp (or, placed late, at the current time)
/// or changes nothing.
void checkOutcome(const ap::DynamicPropagator& p, const char* call, ap::StampOutcome outcome,
                  double t, const Snapshot& before) {
  FUZZ_TRACE("  %s(%.17g) -> %s; now t = %.17g, %s, w %s", call, t, ap::outcomeName(outcome),
             p.time(), describe(p.state().q_WB).c_str(), describe(p.state().w_B).c_str());
  checkState(p, call);
  if (ap::stateHoldsAtStamp(outcome)) {
    // An input placed late (t < time()) leaves the state at the current time, also when the
    // re-advance from its knot failed (FailedStep holds at the current time then).
    const bool late_possible =
        outcome == ap::StampOutcome::Advanced || outcome == ap::StampOutcome::FailedStep;
    const double expected = late_possible ? std::max(t, before.t) : t;
    if (p.time() != expected) {
      fail(call, std::string(ap::outcomeName(outcome)) + " at t = " + std::to_string(t) +
                     " but time() = " + std::to_string(p.time()));
    }
  } else if (!(Snapshot(p) == before)) {
    fail(call, std::string(ap::outcomeName(outcome)) + " changed the state");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);

  ap::DynamicConfig config;
  if (!acceptedBy("RigidBody", [&] { config.body = makeBody(in); })) return 0;
  config.integrator = ap::integratorFromName(readIntegratorCode(in, integratorCodes()));
  config.torque_input = in.flag();
  if (in.flag()) config.max_step = stepValue(in);
  if (in.flag()) config.tolerance = in.value();
  if (in.flag()) config.torque_timeout = stepValue(in);
  if (in.flag()) config.time_policy.max_dt = in.value();
  if (in.flag()) config.time_policy.backward_jump = in.value();
  if (in.flag()) config.initial.q_WB = in.quaternion();
  if (in.flag()) config.initial.w_B = in.flag() ? in.vector3() : Eigen::Vector3d(0, 4, 0.05);
  const double epoch = in.flag() ? 1.7e9 : 0.0;

  FUZZ_TRACE(
      "DynamicPropagator: moments %s, integrator %s, torque_input %d, max_step %.17g, "
      "tolerance %.17g, torque_timeout %.17g, max_dt %.17g, backward_jump %.17g, %s, w0 %s",
      describe(config.body.principalMoments()).c_str(),
      ap::integratorName(config.integrator).c_str(), config.torque_input, config.max_step,
      config.tolerance, config.torque_timeout, config.time_policy.max_dt,
      config.time_policy.backward_jump, describe(config.initial.q_WB).c_str(),
      describe(config.initial.w_B).c_str());
  std::optional<ap::DynamicPropagator> p;
  if (!acceptedBy("DynamicPropagator(config)", [&] { p.emplace(config); })) return 0;
  checkState(*p, "construction");
  const bool exact = p->integrator() == ap::Integrator::Exact;
  const double horizon = std::min(kMaxHorizon, kMaxGridSteps * config.max_step);
  const auto clamp = [&](double t) {
    return p->anchored() && t > p->time() ? std::min(t, p->time() + horizon) : t;
  };

  for (int calls = 0; calls < kMaxCalls && !in.exhausted(); ++calls) {
    const double last = p->anchored() ? p->time() : epoch;
    const Snapshot before(*p);
    switch (in.choice(8)) {
      case 3: {
        const double t = clamp(in.stamp(last));
        const Eigen::Vector3d tau = in.vector3();
        const auto frame = in.flag() ? ap::TorqueFrame::Fixed : ap::TorqueFrame::Body;
        FUZZ_TRACE("setTorque(%.17g, %s, %s)", t, describe(tau).c_str(),
                   frame == ap::TorqueFrame::Fixed ? "fixed" : "body");
        const auto outcome = noThrow("setTorque", [&] {
          return p->setTorque(t, exact ? Eigen::Vector3d::Zero() : tau, frame);
        });
        checkOutcome(*p, "setTorque", outcome, t, before);
        break;
      }
      case 4: {
        const double t = clamp(in.stamp(last));
        const Eigen::Vector3d w = in.vector3();
        FUZZ_TRACE("setRate(%.17g, %s)", t, describe(w).c_str());
        const auto outcome = noThrow("setRate", [&] { return p->setRate(t, w); });
        checkOutcome(*p, "setRate", outcome, t, before);
        break;
      }
      case 5: {
        const double t = in.stamp(last);
        ap::DynamicState x;
        x.q_WB = in.quaternion();
        x.w_B = in.vector3();
        FUZZ_TRACE("setState(%.17g, %s, %s)", t, describe(x.q_WB).c_str(), describe(x.w_B).c_str());
        if (acceptedBy("setState", [&] { p->setState(t, x); })) {
          if (p->time() != t) fail("setState", "time() is not the stamp given");
        } else if (!(Snapshot(*p) == before)) {
          fail("setState", "a refused state changed the propagator");
        }
        checkState(*p, "setState");
        break;
      }
      case 6:
        FUZZ_TRACE("reset()");
        noThrow("reset", [&] { p->reset(); });
        checkState(*p, "reset");
        if (p->anchored()) fail("reset", "still anchored");
        break;
      case 7: {  // a timer: evenly spaced advances
        static const double kPeriods[] = {1e-3, 1e-2, 0.1};
        const double h = kPeriods[in.choice(3)];
        const int n = 1 + static_cast<int>(in.choice(16));
        for (int k = 1; k <= n && calls < kMaxCalls; ++k, ++calls) {
          const Snapshot tick(*p);
          const double t = clamp(last + k * h);
          const auto outcome = noThrow("advanceTo", [&] { return p->advanceTo(t); });
          checkOutcome(*p, "advanceTo", outcome, t, tick);
        }
        break;
      }
      default: {
        const double t = clamp(in.stamp(last));
        const auto outcome = noThrow("advanceTo", [&] { return p->advanceTo(t); });
        checkOutcome(*p, "advanceTo", outcome, t, before);
        break;
      }
    }
  }
  return 0;
}
