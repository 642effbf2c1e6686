#include "attitude_propagator/integrator.h"

#include <stdexcept>

#include "attitude_propagator/dynamic_step.h"
#include "attitude_propagator/kinematic_step.h"

namespace attitude_propagator {

namespace {

using keeps::kConstantRate;
using keeps::kEnergy;
using keeps::kExactFlow;
using keeps::kMomentum;
using keeps::kNothing;
using keeps::kUnitNorm;

// One row per method, in the enumeration's order: adding an integrator means its step function
// and one row here. Columns: id, name, orders (kinematic from instantaneous samples, from
// interval averages, dynamic), samples read, what it keeps, where auto picks it, takes torque,
// restarts from the anchor, step functions.
// - rk4 on sampled rates sees only the linear interpolant at the midpoint: second
//   order from point samples, third from interval means (the linear rate of two means).
// - euler and exp on interval means: the mean carries the rotation angle exactly, second order.
// - exp2 on interval means adds the two-sample coning correction: third order.
constexpr IntegratorInfo kIntegrators[] = {
    {Integrator::Auto, "auto", 0, 0, 0, 0, kNothing, auto_for::kNever, true, false, nullptr,
     nullptr},
    {Integrator::Euler, "euler", 1, 2, 0, 2, kNothing, auto_for::kNever, false, false,
     &kinematicEuler, nullptr},
    {Integrator::Rk4, "rk4", 2, 3, 4, 3, kNothing, auto_for::kTorqued, true, false, &kinematicRk4,
     &DynamicStepper::rk4},
    {Integrator::Exp, "exp", 1, 2, 0, 2, kUnitNorm | kConstantRate, auto_for::kNever, false, false,
     &kinematicExp, nullptr},
    {Integrator::Exp2, "exp2", 2, 3, 0, 3, kUnitNorm | kConstantRate, auto_for::kNever, false,
     false, &kinematicExp2, nullptr},
    {Integrator::Cf4, "cf4", 4, 4, 0, 4, kUnitNorm | kConstantRate, auto_for::kKinematic, false,
     true, &kinematicCf4, nullptr},
    {Integrator::ImplicitMidpoint, "implicit_midpoint", 0, 0, 2, 0, kUnitNorm | kEnergy | kMomentum,
     auto_for::kNever, true, false, nullptr, &DynamicStepper::implicitMidpoint},
    {Integrator::Splitting, "splitting", 0, 0, 2, 0, kUnitNorm | kMomentum, auto_for::kNever, true,
     false, nullptr, &DynamicStepper::splitting},
    {Integrator::Splitting4, "splitting4", 0, 0, 4, 0, kUnitNorm | kMomentum, auto_for::kNever,
     true, false, nullptr, &DynamicStepper::splitting4},
    {Integrator::Dopri5, "dopri5", 0, 0, 0, 0, kNothing, auto_for::kNever, true, false, nullptr,
     &DynamicStepper::dopri5},
    {Integrator::Exact, "exact", 0, 0, 0, 0, kUnitNorm | kEnergy | kMomentum | kExactFlow,
     auto_for::kTorqueFree, false, false, nullptr, &DynamicStepper::exact},
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
  throw std::invalid_argument("model: unknown value '" + name +
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
  throw std::invalid_argument("integrator: unknown value '" + name +
                              "'; accepted: " + joinNames(integratorNames()));
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
