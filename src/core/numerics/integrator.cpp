#include "attitude_propagator/numerics/integrator.h"

#include <stdexcept>

#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/kinematic_step.h"
#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

// The kinematic step functions (KinematicStepFunction, defined and documented in
// kinematic_step.cpp), named only by the rows below.
Eigen::Quaterniond kinematicEuler(const Eigen::Quaterniond&, const RateWindow&, std::size_t,
                                  RateSamples);
Eigen::Quaterniond kinematicRk4(const Eigen::Quaterniond&, const RateWindow&, std::size_t,
                                RateSamples);
Eigen::Quaterniond kinematicExp(const Eigen::Quaterniond&, const RateWindow&, std::size_t,
                                RateSamples);
Eigen::Quaterniond kinematicExp2(const Eigen::Quaterniond&, const RateWindow&, std::size_t,
                                 RateSamples);
Eigen::Quaterniond kinematicCf4(const Eigen::Quaterniond&, const RateWindow&, std::size_t,
                                RateSamples);

namespace {

using keeps::kConstantRate;
using keeps::kEnergy;
using keeps::kExactFlow;
using keeps::kMomentum;
using keeps::kUnitNorm;

// One row per method, in the enumeration's order, each built field by field: a field not named
// keeps IntegratorInfo's default (integrator.h). Adding an integrator means its step function,
// its declaration above and one row appended at the end here (docs/design.md §4.2). The rows
// are also read as text, by cfg/AttitudePropagator.cfg (the reconfigure enum: name and summary)
// and test/fuzz/make_seeds.py (name and step functions): a row runs from its line
// `IntegratorInfo m;` to its line `return m;`, with one `m.name = "...";` and one
// `m.summary = "...";` statement (a literal string each, no concatenation).
constexpr IntegratorInfo kIntegrators[] = {
    [] {
      IntegratorInfo m;
      m.id = Integrator::Auto;
      m.name = "auto";
      m.summary =
          "cf4 kinematic (exp2 or rk4 where the stream calls for it), exact torque-free, else rk4";
      m.takes_torque = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Euler;
      m.name = "euler";
      m.summary = "kinematic, order 1";
      m.kinematic_step = &kinematicEuler;
      m.kinematic_order = 1;
      m.averaged_order = 2;  // the interval mean carries the rotation angle exactly
      m.samples = 2;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Rk4;
      m.name = "rk4";
      m.summary = "kinematic order 2 from samples, dynamic order 4";
      m.kinematic_step = &kinematicRk4;
      // On sampled rates rk4 sees only the linear interpolant at the midpoint: second order
      // from point samples, third from interval means (the linear rate of two means).
      m.kinematic_order = 2;
      m.averaged_order = 3;
      m.samples = 3;
      m.dynamic_step = &DynamicStepper::rk4;
      m.dynamic_order = 4;
      m.takes_torque = true;
      m.auto_for = auto_for::kTorqued;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Exp;
      m.name = "exp";
      m.summary = "kinematic, exact for a constant rate";
      m.kinematic_step = &kinematicExp;
      m.kinematic_order = 1;
      m.averaged_order = 2;  // the interval mean carries the rotation angle exactly
      m.samples = 2;
      m.keeps = kUnitNorm | kConstantRate;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Exp2;
      m.name = "exp2";
      m.summary = "kinematic, order 2";
      m.kinematic_step = &kinematicExp2;
      m.kinematic_order = 2;
      m.averaged_order = 3;  // interval means: the two-sample coning correction
      m.samples = 3;
      m.keeps = kUnitNorm | kConstantRate;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Cf4;
      m.name = "cf4";
      m.summary = "kinematic, order 4";
      m.kinematic_step = &kinematicCf4;
      m.kinematic_order = 4;
      m.averaged_order = 4;
      m.samples = 4;
      m.keeps = kUnitNorm | kConstantRate;
      m.auto_for = auto_for::kKinematic;
      m.restart_from_anchor = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::ImplicitMidpoint;
      m.name = "implicit_midpoint";
      m.summary = "dynamic, order 2, keeps energy and |M|";
      m.dynamic_step = &DynamicStepper::implicitMidpoint;
      m.dynamic_order = 2;
      m.keeps = kUnitNorm | kEnergy | kMomentum;
      m.takes_torque = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Splitting;
      m.name = "splitting";
      m.summary = "dynamic, order 2, Strang splitting of the free rotor";
      m.dynamic_step = &DynamicStepper::splitting;
      m.dynamic_order = 2;
      m.keeps = kUnitNorm | kMomentum;
      m.takes_torque = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Splitting4;
      m.name = "splitting4";
      m.summary = "dynamic, order 4, Yoshida composition of splitting";
      m.dynamic_step = &DynamicStepper::splitting4;
      m.dynamic_order = 4;
      m.keeps = kUnitNorm | kMomentum;
      m.takes_torque = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Dopri5;
      m.name = "dopri5";
      m.summary = "dynamic, adaptive 5(4)";
      m.dynamic_step = &DynamicStepper::dopri5;  // adaptive: no declared order
      m.takes_torque = true;
      return m;
    }(),
    [] {
      IntegratorInfo m;
      m.id = Integrator::Exact;
      m.name = "exact";
      m.summary = "dynamic, torque-free closed form";
      m.dynamic_step = &DynamicStepper::exact;  // the solution: no declared order
      m.keeps = kUnitNorm | kEnergy | kMomentum | kExactFlow;
      m.auto_for = auto_for::kTorqueFree;
      return m;
    }(),
};

constexpr std::size_t kRows = sizeof(kIntegrators) / sizeof(kIntegrators[0]);

constexpr bool rowsInEnumOrder() {
  for (std::size_t i = 0; i < kRows; ++i) {
    if (static_cast<std::size_t>(kIntegrators[i].id) != i) return false;
  }
  return true;
}
static_assert(rowsInEnumOrder(), "the rows must follow the order of enum class Integrator");

constexpr bool windowsFit() {
  for (const IntegratorInfo& row : kIntegrators) {
    if (row.samples > static_cast<int>(RateWindow::kCapacity)) return false;
  }
  return true;
}
static_assert(windowsFit(), "a method reads more samples than RateWindow::kCapacity holds");

constexpr bool sameName(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {
    ++a;
    ++b;
  }
  return *a == *b;
}

constexpr bool namesValidAndUnique() {
  for (std::size_t i = 0; i < kRows; ++i) {
    const char* c = kIntegrators[i].name;
    if (*c == '\0') return false;
    for (; *c != '\0'; ++c) {
      if (!((*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '_')) return false;
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (sameName(kIntegrators[i].name, kIntegrators[j].name)) return false;
    }
  }
  return true;
}
static_assert(namesValidAndUnique(), "every row needs its own name of [a-z0-9_]");

constexpr bool kinematicRowsReadAnInterval() {
  for (std::size_t i = 1; i < kRows; ++i) {
    if ((kIntegrators[i].kinematic_step != nullptr) != (kIntegrators[i].samples >= 2)) {
      return false;
    }
  }
  return true;
}
static_assert(kinematicRowsReadAnInterval(),
              "a kinematic row reads at least two samples (an interval); no other row reads any");

}  // namespace

const std::vector<IntegratorInfo>& integratorTable() {
  static const std::vector<IntegratorInfo> table(kIntegrators, kIntegrators + kRows);
  return table;
}

const IntegratorInfo& integratorInfo(Integrator integrator) {
  const auto i = static_cast<std::size_t>(integrator);
  if (i >= kRows) throw std::invalid_argument("unknown integrator id");
  return kIntegrators[i];
}

Model modelFromName(const std::string& name) {
  if (name == "auto") return Model::Auto;
  if (name == "kinematic") return Model::Kinematic;
  if (name == "dynamic") return Model::Dynamic;
  throw std::invalid_argument("model: unknown value '" + logText(name) +
                              "'; accepted: auto kinematic dynamic");
}

std::string modelName(Model model) {
  switch (model) {
    case Model::Auto:
      return "auto";
    case Model::Kinematic:
      return "kinematic";
    case Model::Dynamic:
      return "dynamic";
  }
  return "unknown";
}

Integrator integratorFromName(const std::string& name) {
  for (const auto& row : kIntegrators) {
    if (name == row.name) return row.id;
  }
  throw std::invalid_argument("integrator: unknown value '" + logText(name) +
                              "'; accepted: " + joinNames(integratorNames()));
}

Integrator integratorFromName(const std::string& name, Model model) {
  // auto drives every model (integratorsFor leaves it out).
  if (name == integratorName(Integrator::Auto)) return Integrator::Auto;
  std::vector<std::string> accepted{integratorName(Integrator::Auto)};
  for (Integrator m : integratorsFor(model)) {
    if (name == integratorName(m)) return m;
    accepted.push_back(integratorName(m));
  }
  throw std::invalid_argument("integrator: unknown value '" + name + "' for the " +
                              modelName(model) + " model; accepted: " + joinNames(accepted));
}

std::string integratorName(Integrator integrator) { return integratorInfo(integrator).name; }

bool supportsKinematic(Integrator integrator) {
  return integrator == Integrator::Auto || integratorInfo(integrator).kinematic_step != nullptr;
}

bool supportsDynamic(Integrator integrator) {
  return integrator == Integrator::Auto || integratorInfo(integrator).dynamic_step != nullptr;
}

int declaredOrder(Integrator integrator, Model model) {
  const IntegratorInfo& row = integratorInfo(integrator);
  return model == Model::Dynamic ? row.dynamic_order : row.kinematic_order;
}

std::vector<Integrator> integratorsFor(Model model) {
  std::vector<Integrator> methods;
  for (const auto& row : kIntegrators) {
    const bool drives = model == Model::Kinematic ? row.kinematic_step != nullptr
                        : model == Model::Dynamic ? row.dynamic_step != nullptr
                                                  : false;
    if (drives) methods.push_back(row.id);
  }
  return methods;
}

Integrator autoIntegrator(Model model, bool torque_input) {
  const unsigned wanted = model == Model::Kinematic ? auto_for::kKinematic
                          : torque_input            ? auto_for::kTorqued
                                                    : auto_for::kTorqueFree;
  for (const auto& row : kIntegrators) {
    if (row.auto_for & wanted) return row.id;
  }
  throw std::logic_error("integrator table: no method for auto");
}

std::vector<std::string> integratorNames() {
  std::vector<std::string> names;
  for (const auto& row : kIntegrators) names.emplace_back(row.name);
  return names;
}

std::vector<std::string> integratorNames(const std::vector<Integrator>& integrators) {
  std::vector<std::string> names;
  for (Integrator m : integrators) names.push_back(integratorName(m));
  return names;
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const auto& name : names) joined += (joined.empty() ? "" : " ") + name;
  return joined;
}

}  // namespace attitude_propagator
