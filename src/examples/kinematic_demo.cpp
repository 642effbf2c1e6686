// Core-only demo: propagates the coning motion (docs/numerics.md §8) from a built-in 200 Hz stream
// of body rates with cf4 and prints the orientation as it evolves next to the closed form. Usage:
// kinematic_demo [integrator] [seconds]
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace ap = attitude_propagator;

namespace {

constexpr double kSampleRate = 200.0;  // Hz

}  // namespace

int main(int argc, char** argv) {
  try {
    const ap::ConingMotion cone{0.1, M_PI};  // half-angle 0.1 rad, one cone every 2 s
    ap::KinematicConfig config;
    config.integrator = ap::integratorFromName(argc > 1 ? argv[1] : "cf4", ap::Model::Kinematic);
    config.initial_q_WB = cone.attitude(0.0);
    const double duration = argc > 2 ? std::stod(argv[2]) : 5.0;
    ap::KinematicPropagator propagator(config);
    std::printf("coning motion, half-angle %.2f rad, cone rate %.2f rad/s, %s at %.0f Hz\n",
                cone.beta, cone.omega, ap::integratorName(propagator.integrator()).c_str(),
                kSampleRate);
    std::printf("%8s  %10s %10s %10s %10s  %12s\n", "t [s]", "x", "y", "z", "w", "error [rad]");
    const int samples = static_cast<int>(duration * kSampleRate);
    for (int k = 0; k <= samples; ++k) {
      const double t = k / kSampleRate;
      propagator.addSample(t, cone.bodyRate(t));
      if (k % static_cast<int>(kSampleRate / 4) != 0) continue;
      const Eigen::Quaterniond& q = propagator.orientation();
      std::printf("%8.2f  %10.6f %10.6f %10.6f %10.6f  %12.3e\n", t, q.x(), q.y(), q.z(), q.w(),
                  ap::rotationAngle(q, cone.attitude(t)));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kinematic_demo: %s\n", e.what());
    return 1;
  }
  return 0;
}
