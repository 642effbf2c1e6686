#include "dynamic_sweep.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/numerics/torque_free_motion.h"
#include "methods.h"
#include "reference.h"

namespace bench {

namespace {

using ap::DynamicState;
using ap::Integrator;

constexpr double kNormLost = 0.1;  // see kinematic_sweep.cpp
constexpr double kDiverged = 1.0;  // rad, or a relative energy change of this size
// dopri5 is swept over its tolerance at the output step of the node's default grid (max_step =
// 1/publish_rate = 0.01 s): a propagator must produce a state that often, whatever its method.
constexpr double kDopri5OutputStep = 0.01;
// Down to kMinTolerance: a DynamicPropagator refuses a tighter one (below round-off).
const std::vector<double> kDopri5Tolerances = {1e-4, 1e-5,  1e-6,  1e-7, 1e-8,
                                               1e-9, 1e-10, 1e-11, 1e-12};

ap::RigidBody bodyOf(const DynamicScene& scene) {
  // Hairer-Lubich-Wanner's body (2, 1, 2/3) breaks the triangle inequality: a valid
  // mathematical test case, not a physical body, so the check is waived for the benchmarks.
  return ap::RigidBody::fromPrincipalMoments(scene.moments,
                                             ap::RigidBody::TriangleInequality::Ignore);
}

/// The truth at the scene's check times: the exact solution when the scene is torque-free and
/// the core provides it for this body, otherwise the Bulirsch-Stoer reference.
struct Truth {
  std::vector<double> times;
  std::vector<DynamicState> states;     // what the methods are judged against
  std::vector<DynamicState> reference;  // Bulirsch-Stoer: judges `exact` itself
  std::optional<ap::TorqueFreeMotion> exact;
};

std::optional<ap::TorqueFreeMotion> exactMotion(const DynamicScene& scene) {
  if (!scene.torqueFree()) return std::nullopt;
  try {
    return ap::TorqueFreeMotion(bodyOf(scene), scene.initial);
  } catch (const std::logic_error& e) {  // a form the core does not provide yet
    std::fprintf(stderr, "bench: %s: no exact solution (%s); judged by Bulirsch-Stoer\n",
                 scene.name.c_str(), e.what());
    return std::nullopt;
  }
}

Truth makeTruth(const DynamicScene& scene) {
  Truth truth;
  const long checks = std::lround(scene.duration / scene.check_interval);
  for (long i = 1; i <= checks; ++i) truth.times.push_back(i * scene.check_interval);
  truth.reference = referenceStates(scene.moments, scene.initial, scene.torque_B, truth.times);
  truth.exact = exactMotion(scene);
  truth.states = truth.reference;
  if (truth.exact) {
    for (std::size_t i = 0; i < truth.times.size(); ++i) {
      truth.states[i] = truth.exact->evaluate(truth.times[i]);
    }
  }
  return truth;
}

DynamicState truthAt(const DynamicScene& scene, const Truth& truth, double t) {
  if (truth.exact) return truth.exact->evaluate(t);
  return referenceStates(scene.moments, scene.initial, scene.torque_B, {t}).front();
}

/// Energy 1/2 w.Iw, |M| = |I w|, and the side of the separatrix (docs/numerics.md §6, moments
/// sorted I1 < I2 < I3, Delta2 = G^2 - 2T I2): +-1 when M circulates about +-e1, +-2 about +-e3.
struct Invariants {
  double energy;
  double momentum;
  int side;
};

Invariants invariantsOf(const Eigen::Vector3d& I, const Eigen::Vector3d& w) {
  const Eigen::Vector3d M = I.cwiseProduct(w);
  Invariants inv{0.5 * w.dot(M), M.norm(), 0};
  int small = 0, large = 0;
  for (int i = 1; i < 3; ++i) {
    if (I[i] < I[small]) small = i;
    if (I[i] > I[large]) large = i;
  }
  const int middle = 3 - small - large;
  const double delta2 = M.squaredNorm() - 2.0 * inv.energy * I[middle];
  inv.side = delta2 < 0 ? (M[small] > 0 ? 1 : -1) : (M[large] > 0 ? 2 : -2);
  return inv;
}

bool isTriaxial(const Eigen::Vector3d& I) { return I[0] != I[1] && I[1] != I[2] && I[0] != I[2]; }

/// Running error and invariant drift of one run, fed a state at each check time.
class Score {
 public:
  explicit Score(const DynamicScene& scene)
      : I_(scene.moments),
        torque_free_(scene.torqueFree()),
        check_side_(torque_free_ && isTriaxial(scene.moments)),
        inv0_(invariantsOf(I_, scene.initial.w_B)) {}

  void add(const DynamicState& x, const DynamicState& truth) {
    last_err_ = ap::rotationAngle(x.q_WB, truth.q_WB);
    if (!std::isfinite(last_err_) || !x.w_B.allFinite()) nonfinite_ = true;
    err_ = std::max(err_, last_err_);
    addInvariants(x);
  }

  void addInvariants(const DynamicState& x) {
    if (!torque_free_) return;  // a torque changes E and |M|: nothing to conserve
    const Invariants inv = invariantsOf(I_, x.w_B);
    energy_ = std::max(energy_, std::abs(inv.energy - inv0_.energy) / inv0_.energy);
    momentum_ = std::max(momentum_, std::abs(inv.momentum - inv0_.momentum) / inv0_.momentum);
    if (check_side_ && inv.side != inv0_.side) wrong_side_ = true;
  }

  void addNorm(double norm_error) { norm_ = std::max(norm_, std::abs(norm_error)); }

  void fill(Result& r) const {
    r.err_rad = nonfinite_ ? NAN : err_;
    r.final_err_rad = nonfinite_ ? NAN : last_err_;
    if (torque_free_) {
      r.energy_rel_drift = energy_;
      r.momentum_rel_drift = momentum_;
    }
    r.norm_err = norm_;
    r.status = nonfinite_                                     ? "nonfinite"
               : wrong_side_                                  ? "wrong_side"
               : norm_ > kNormLost                            ? "norm_lost"
               : last_err_ > kDiverged || energy_ > kDiverged ? "diverged"
                                                              : "ok";
  }

 private:
  Eigen::Vector3d I_;
  bool torque_free_;
  bool check_side_;  // the separatrix sides exist only for a torque-free triaxial body
  Invariants inv0_;
  double err_ = 0.0, last_err_ = 0.0, energy_ = 0.0, momentum_ = 0.0, norm_ = 0.0;
  bool nonfinite_ = false, wrong_side_ = false;
};

Integrator autoChoice(const DynamicScene& scene) {
  ap::DynamicConfig config;
  config.body = bodyOf(scene);
  config.torque_input = !scene.torqueFree();
  config.initial = scene.initial;
  return ap::DynamicPropagator(config).integrator();
}

Result baseResult(const DynamicScene& scene, Integrator method, double dt, long steps) {
  Result r;
  r.scene = scene.name;
  r.method = ap::integratorName(method);
  r.is_auto = method == autoChoice(scene);
  r.dt = dt;
  r.omega_dt = dt * scene.max_rate;
  r.steps = steps;
  return r;
}

/// A method driven as the propagator drives it: a stepper on the principal state (`exact`'s
/// stepper follows its cached closed form from step to step).
class Driver {
 public:
  Driver(const DynamicScene& scene, Integrator method, double tolerance = 1e-9)
      : stepper_(method, bodyOf(scene), tolerance),
        x0_(stepper_.toPrincipal(scene.initial)),
        torque_(stepper_.toPrincipal(ap::TorqueInput{scene.torque_B, ap::TorqueFrame::Body})) {
    reset();
  }

  void reset() {
    x_ = x0_;
    stepper_.setStepSizeHint(0.0);
  }

  /// Advances by dt; returns |q| - 1 before renormalisation.
  double step(double dt) {
    ap::StepInfo info;
    stepper_.stepPrincipal(x_, torque_, dt, &info);
    return info.norm_error;
  }

  DynamicState state() const { return stepper_.fromPrincipal(x_); }
  double probe() const { return x_.q_WP.w(); }

 private:
  ap::DynamicStepper stepper_;
  ap::PrincipalState x0_;
  ap::PrincipalTorque torque_;
  ap::PrincipalState x_;
};

/// Whether the method can run the scene: one that takes no torque only a torque-free one, and
/// the exact solution only where the core provides the closed form.
bool runs(Integrator method, const DynamicScene& scene, const Truth& truth) {
  if (isExactSolution(method)) return truth.exact.has_value();
  return ap::integratorInfo(method).takes_torque || scene.torqueFree();
}

/// The untimed pass: steps of dt to the end, scored at the check times.
void measureErrors(const DynamicScene& scene, const Truth& truth, Driver& driver, double dt,
                   long steps, bool judge_by_reference, Result& r) {
  const long check_every = std::lround(scene.check_interval / dt);
  Score score(scene);
  driver.reset();
  for (long k = 1; k <= steps; ++k) {
    score.addNorm(driver.step(dt));
    if (k % check_every != 0) continue;
    const std::size_t i = k / check_every - 1;
    score.add(driver.state(), judge_by_reference ? truth.reference[i] : truth.states[i]);
  }
  score.fill(r);
}

double timedRun(Driver& driver, double dt, long steps) {
  driver.reset();
  for (long k = 1; k <= steps; ++k) driver.step(dt);
  return driver.probe();
}

std::vector<Integrator> fixedStepMethods(const DynamicScene& scene, const Truth& truth) {
  std::vector<Integrator> methods;
  for (Integrator m : methodsFor(ap::Model::Dynamic)) {
    if (m == Integrator::Dopri5) continue;  // swept over its tolerance instead
    if (runs(m, scene, truth)) methods.push_back(m);
  }
  return methods;
}

void sweepOneStep(const DynamicScene& scene, const Truth& truth, double dt,
                  const TimingOptions& timing, std::FILE* out) {
  const long steps = std::lround(scene.duration / dt);
  const auto methods = fixedStepMethods(scene, truth);
  std::vector<Driver> drivers;
  for (Integrator m : methods) drivers.emplace_back(scene, m);
  std::vector<Run> runs;
  for (Driver& d : drivers) runs.push_back([&d, dt, steps] { return timedRun(d, dt, steps); });
  const std::vector<double> ns = medianNsPerStep(runs, steps, timing);
  for (std::size_t m = 0; m < methods.size(); ++m) {
    Result r = baseResult(scene, methods[m], dt, steps);
    // `exact` is judged by the independent reference (against itself it would score zero).
    measureErrors(scene, truth, drivers[m], dt, steps, isExactSolution(methods[m]), r);
    r.ns_per_step = ns[m];
    writeRow(out, r);
  }
}

void sweepDopri5(const DynamicScene& scene, const Truth& truth, const TimingOptions& timing,
                 std::FILE* out) {
  const double dt = kDopri5OutputStep;
  const long steps = std::lround(scene.duration / dt);
  for (double tol : kDopri5Tolerances) {
    Driver driver(scene, Integrator::Dopri5, tol);
    Result r = baseResult(scene, Integrator::Dopri5, dt, steps);
    r.tolerance = tol;
    measureErrors(scene, truth, driver, dt, steps, false, r);
    r.ns_per_step =
        medianNsPerStep({[&] { return timedRun(driver, dt, steps); }}, steps, timing).front();
    writeRow(out, r);
  }
}

double maxRate(const DynamicScene& scene, const Truth& truth) {
  double rate = scene.initial.w_B.norm();
  for (const DynamicState& x : truth.reference) rate = std::max(rate, x.w_B.norm());
  return rate;
}

}  // namespace

void runDynamicSweep(std::vector<DynamicScene>& scenes, const TimingOptions& timing,
                     std::FILE* out) {
  for (DynamicScene& scene : scenes) {
    const Truth truth = makeTruth(scene);
    scene.max_rate = maxRate(scene, truth);
    for (double dt : scene.steps) sweepOneStep(scene, truth, dt, timing, out);
    sweepDopri5(scene, truth, timing, out);
    std::fprintf(stderr, "bench: %s done (truth: %s)\n", scene.name.c_str(),
                 truth.exact ? truth.exact->formName() : "Bulirsch-Stoer, long double, 1e-16");
  }
}

void runDynamicStability(DynamicScene scene, double duration, std::FILE* out) {
  scene.duration = duration;
  const Truth truth = makeTruth(scene);  // for max_rate and the exact solution
  scene.max_rate = maxRate(scene, truth);
  for (int i = 0; i <= 16; ++i) {
    const double omega_dt = 1e-3 * std::pow(10.0, i / 4.0);  // 1e-3 .. 10, four per decade
    const double dt = omega_dt / scene.max_rate;
    const long steps = std::max(1L, std::lround(duration / dt));
    const DynamicState x_end = truthAt(scene, truth, steps * dt);
    // `exact` is judged by the independent reference (against itself it would score zero).
    const DynamicState x_end_reference =
        referenceStates(scene.moments, scene.initial, scene.torque_B, {steps * dt}).front();
    for (Integrator m : methodsFor(ap::Model::Dynamic)) {
      if (!runs(m, scene, truth)) continue;
      Driver driver(scene, m);
      Score score(scene);
      for (long k = 1; k <= steps; ++k) {
        score.addNorm(driver.step(dt));
        if (k < steps) score.addInvariants(driver.state());
      }
      score.add(driver.state(), isExactSolution(m) ? x_end_reference : x_end);
      Result r = baseResult(scene, m, dt, steps);
      if (m == Integrator::Dopri5) r.tolerance = 1e-9;
      score.fill(r);
      writeRow(out, r);
    }
  }
}

void runInvariants(const DynamicScene& scene, double h, double duration, double every,
                   std::FILE* out) {
  const long steps = std::lround(duration / h);
  const long out_every = std::lround(every / h);
  const auto exact = exactMotion(scene);
  for (Integrator m : methodsFor(ap::Model::Dynamic)) {
    if (isExactSolution(m)) continue;  // constant to round-off by construction
    Driver driver(scene, m, 1e-8);
    const Invariants inv0 = invariantsOf(scene.moments, scene.initial.w_B);
    for (long k = 1; k <= steps; ++k) {
      driver.step(h);
      if (k % out_every != 0) continue;
      const DynamicState x = driver.state();
      const Invariants inv = invariantsOf(scene.moments, x.w_B);
      const double err = exact ? ap::rotationAngle(x.q_WB, exact->evaluate(k * h).q_WB) : NAN;
      std::fprintf(out, "%s,%g,%s,%g,%.6g,%.6g,%s\n", ap::integratorName(m).c_str(), h,
                   m == Integrator::Dopri5 ? "1e-08" : "", k * h,
                   std::abs(inv.energy - inv0.energy) / inv0.energy,
                   std::abs(inv.momentum - inv0.momentum) / inv0.momentum, field(err).c_str());
    }
  }
}

}  // namespace bench
