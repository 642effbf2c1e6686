// Fuzz target: the parameter validator. The input overrides any of the node's parameters
// (valid and invalid names of models, integrators, inputs and frames; vectors of any length;
// arbitrary numbers). validateParameters may refuse with std::invalid_argument only. What it
// accepts must start: the propagator is constructed from the NodeConfig without an exception
// and driven the way the node drives it (kinematic: IMU samples at 200 Hz; dynamic: timer ticks
// at publish_rate, a torque and a rate sample if those inputs are on, then a gap of max_dt),
// with no clamp on the work, so a configuration that makes one call run away shows up as a
// libFuzzer timeout. Oracle as in the other targets: finite unit orientation, finite rate and
// kinetic energy after every call.
#include <string>
#include <vector>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/numerics/integrator.h"
#include "fuzz_support.h"

namespace ap = attitude_propagator;
using namespace attitude_propagator_fuzz;

namespace {

std::string pick(ByteReader& in, const std::vector<std::string>& options) {
  return options[in.choice(options.size())];
}

/// A vector of 0..7 entries, each an ordinary positive number or anything at all.
std::vector<double> vectorOfAnyLength(ByteReader& in) {
  static const double kOrdinary[] = {1.0, 2.0, 3.0, 0.5, 0.1, 0.0, 20.0, 0.25};
  std::vector<double> v(in.choice(8));
  for (double& x : v) x = in.flag() ? kOrdinary[in.choice(8)] : in.value();
  return v;
}

/// A vector of the expected size most of the time, of any size otherwise.
std::vector<double> vectorOfSize(ByteReader& in, std::size_t n) {
  if (in.flag()) return vectorOfAnyLength(in);
  std::vector<double> v(n);
  for (double& x : v) x = in.value();
  return v;
}

/// The integrator values tried: every name the core accepts, by its code (integratorCodes()),
/// then names it refuses. make_seeds.py's CHOICES["integrator"] encodes an index into this list
/// (test/checks/integrator_lists.sh checks the two agree).
std::vector<std::string> integratorChoices() {
  std::vector<std::string> names = integratorCodes();
  for (const char* refused : {"", "rk5"}) names.emplace_back(refused);
  return names;
}

double number(ByteReader& in, const std::vector<double>& ordinary) {
  return in.flag() ? ordinary[in.choice(ordinary.size())] : in.value();
}

ap::Parameters readParameters(ByteReader& in) {
  ap::Parameters p;  // every field not overridden keeps its default
  if (in.flag()) p.model = pick(in, {"auto", "kinematic", "dynamic", "", "Dynamic"});
  if (in.flag()) {
    static const std::vector<std::string> integrators = integratorChoices();
    p.integrator = readIntegratorCode(in, integrators);
  }
  if (in.flag()) p.rate_input = pick(in, {"imu", "twist", "none", "IMU"});
  if (in.flag()) p.torque_input = in.flag();
  if (in.flag()) p.torque_frame = pick(in, {"body", "fixed", "world"});
  if (in.flag()) p.torque_timeout = number(in, {0.0, 0.5, 1e-9});
  if (in.flag()) p.inertia = in.flag() ? std::vector<double>{1, 2, 3} : vectorOfAnyLength(in);
  if (in.flag()) p.initial_orientation = vectorOfSize(in, 4);
  if (in.flag()) p.initial_angular_velocity = vectorOfSize(in, 3);
  if (in.flag()) p.fixed_frame = pick(in, {"world", "base_link", "", "/world", "odom"});
  if (in.flag()) p.body_frame = pick(in, {"base_link", "world", "", "/base_link", "imu"});
  if (in.flag()) p.publish_tf = in.flag();
  if (in.flag()) p.reverse_tf = in.flag();
  if (in.flag()) p.publish_rate = number(in, {100.0, 1.0, 1000.0, 1e9, 0.5});
  if (in.flag()) p.max_step = number(in, {0.0, 0.005, 1e-12, 1.0});
  if (in.flag()) p.max_dt = number(in, {1.0, 0.1, 10.0, 1e-9});
  if (in.flag()) p.tolerance = number(in, {1e-9, 1e-6, 1e-300, 1e-16});
  if (in.flag()) p.angular_velocity_stddev = number(in, {0.0, 0.01, 1e300});
  return p;
}

void checkKinematic(const ap::KinematicPropagator& p, const char* after) {
  requireUnit(p.orientation(), after);
  requireFinite(p.rate(), "rate", after);
}

void checkDynamic(const ap::DynamicPropagator& p, const char* after) {
  FUZZ_TRACE("%s: t = %.17g, %s, w %s", after, p.time(), describe(p.state().q_WB).c_str(),
             describe(p.state().w_B).c_str());
  requireUnit(p.state().q_WB, after);
  requireFinite(p.state().w_B, "rate", after);
  requireFinite(p.kineticEnergy(), "kineticEnergy", after);
}

void driveKinematic(const ap::NodeConfig& config, ByteReader& in, double epoch) {
  ap::KinematicPropagator p = noThrow("KinematicPropagator(accepted config)",
                                      [&] { return ap::KinematicPropagator(config.kinematic); });
  checkKinematic(p, "construction");
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d w = in.flag() ? in.vector3() : Eigen::Vector3d(0.1, -0.2, 0.3);
    const auto outcome = noThrow("addSample", [&] { return p.addSample(epoch + k / 200.0, w); });
    FUZZ_TRACE("addSample(%.17g, %s) -> %s", epoch + k / 200.0, describe(w).c_str(),
               ap::outcomeName(outcome));
    checkKinematic(p, "addSample");
  }
}

void driveDynamic(const ap::NodeConfig& config, ByteReader& in, double epoch) {
  ap::DynamicPropagator p = noThrow("DynamicPropagator(accepted config)",
                                    [&] { return ap::DynamicPropagator(*config.dynamic); });
  checkDynamic(p, "construction");
  const double period = 1.0 / config.parameters.publish_rate;
  for (int k = 0; k < 8; ++k) {
    const double t = epoch + k * period;
    if (k == 2 && config.torque_input) {
      const Eigen::Vector3d tau = in.flag() ? in.vector3() : Eigen::Vector3d(0.0, 5.0, 0.0);
      noThrow("setTorque", [&] { return p.setTorque(t, tau, config.torque_frame); });
      checkDynamic(p, "setTorque");
    }
    if (k == 3 && config.rate_input != ap::RateInput::None) {
      const Eigen::Vector3d w = in.flag() ? in.vector3() : Eigen::Vector3d(0.0, 4.0, 0.05);
      noThrow("setRate", [&] { return p.setRate(t, w); });
      checkDynamic(p, "setRate");
    }
    noThrow("advanceTo", [&] { return p.advanceTo(t); });
    checkDynamic(p, "advanceTo");
  }
  // The longest gap the time policy still integrates across.
  noThrow("advanceTo", [&] { return p.advanceTo(p.time() + config.parameters.max_dt); });
  checkDynamic(p, "advanceTo (max_dt ahead)");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const ap::Parameters parameters = readParameters(in);
  const double epoch = in.flag() ? 1.7e9 : 0.0;
  if (tracing()) {
    forEachParameter(parameters, [](const char* name, const auto& value, const char*, const char*) {
      FUZZ_TRACE("%s: %s", name, ap::formatParameter(value).c_str());
    });
  }
  ap::NodeConfig config;
  if (!acceptedBy("validateParameters", [&] { config = ap::validateParameters(parameters); })) {
    return 0;
  }
  if (config.model == ap::Model::Kinematic) {
    driveKinematic(config, in, epoch);
  } else if (config.dynamic) {
    driveDynamic(config, in, epoch);
  } else {
    fail("validateParameters", "dynamic model without a DynamicConfig");
  }
  return 0;
}
