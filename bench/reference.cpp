#include "reference.h"

#include <array>
#include <cmath>

#include <boost/numeric/odeint.hpp>

#include "attitude_propagator/quaternion.h"

namespace bench {

namespace {

namespace odeint = boost::numeric::odeint;
using OdeState = std::array<double, 7>;  // q (w, x, y, z), w_B (x, y, z)

constexpr double kTolerance = 1e-13;

struct EulerEquations {
  Eigen::Vector3d I;
  Eigen::Vector3d tau;

  void operator()(const OdeState& x, OdeState& dxdt, double /*t*/) const {
    const Eigen::Vector3d w(x[4], x[5], x[6]);
    // 1/2 q (x) (0, w) = 1/2 (-v.w, q_w w + v x w)
    const Eigen::Vector3d v(x[1], x[2], x[3]);
    const Eigen::Vector3d dv = 0.5 * (x[0] * w + v.cross(w));
    const Eigen::Vector3d dw = (I.cwiseProduct(w).cross(w) + tau).cwiseQuotient(I);
    dxdt = {-0.5 * v.dot(w), dv.x(), dv.y(), dv.z(), dw.x(), dw.y(), dw.z()};
  }
};

OdeState pack(const ap::DynamicState& x) {
  return {x.q_WB.w(), x.q_WB.x(), x.q_WB.y(), x.q_WB.z(), x.w_B.x(), x.w_B.y(), x.w_B.z()};
}

ap::DynamicState unpack(const OdeState& s) {
  ap::DynamicState x;
  x.q_WB = Eigen::Quaterniond(s[0], s[1], s[2], s[3]).normalized();
  x.w_B = Eigen::Vector3d(s[4], s[5], s[6]);
  return x;
}

}  // namespace

std::vector<ap::DynamicState> referenceStates(const Eigen::Vector3d& moments,
                                              const ap::DynamicState& x0,
                                              const Eigen::Vector3d& tau_B,
                                              const std::vector<double>& times) {
  odeint::bulirsch_stoer<OdeState> stepper(kTolerance, kTolerance);
  const EulerEquations system{moments, tau_B};
  OdeState state = pack(x0);
  std::vector<ap::DynamicState> out;
  double t = 0.0;
  for (double target : times) {
    if (target > t) {
      odeint::integrate_adaptive(stepper, system, state, t, target, 1e-3);
      t = target;
    }
    out.push_back(unpack(state));
  }
  return out;
}

double referenceSelfCheck() {
  const Eigen::Vector3d I(3.0, 2.0, 1.5);
  const Eigen::Vector3d tau(0.0, 0.0, 0.2);  // along principal axis 3, from rest
  std::vector<double> times;
  for (int k = 1; k <= 10; ++k) times.push_back(k);
  const auto states = referenceStates(I, ap::DynamicState{}, tau, times);
  double worst = 0.0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    const double angle = tau.z() * t * t / (2.0 * I.z());
    const Eigen::Quaterniond truth(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
    worst = std::max(worst, ap::rotationAngle(states[i].q_WB, truth));
  }
  return worst;
}

}  // namespace bench
