#include "attitude_propagator/integrator.h"

#include <array>
#include <stdexcept>

namespace attitude_propagator {

namespace {

struct IntegratorEntry {
  Integrator id;
  const char* name;
  bool kinematic;
  bool dynamic;
  int kinematic_order;  // from rate samples
  int dynamic_order;    // on the Euler equations
};

// One row per method: adding an integrator means one row here and one step function.
constexpr std::array<IntegratorEntry, 11> kIntegrators{{
    {Integrator::Auto, "auto", true, true, 0, 0},
    {Integrator::Euler, "euler", true, false, 1, 0},
    // RK4 on sampled rates sees only the linear interpolant at the midpoint (REFERENCE §2).
    {Integrator::Rk4, "rk4", true, true, 2, 4},
    {Integrator::Exp, "exp", true, false, 1, 0},
    {Integrator::Exp2, "exp2", true, false, 2, 0},
    {Integrator::Cf4, "cf4", true, false, 4, 0},
    {Integrator::ImplicitMidpoint, "implicit_midpoint", false, true, 0, 2},
    {Integrator::Splitting, "splitting", false, true, 0, 2},
    {Integrator::Splitting4, "splitting4", false, true, 0, 4},
    {Integrator::Dopri5, "dopri5", false, true, 0, 0},
    {Integrator::Exact, "exact", false, true, 0, 0},
}};

const IntegratorEntry& entry(Integrator id) {
  for (const auto& e : kIntegrators) {
    if (e.id == id) return e;
  }
  throw std::invalid_argument("unknown integrator id");
}

}  // namespace

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
  for (const auto& e : kIntegrators) {
    if (name == e.name) return e.id;
  }
  throw std::invalid_argument("integrator: unknown value '" + name +
                              "'; accepted: " + integratorNames());
}

std::string integratorName(Integrator integrator) { return entry(integrator).name; }

bool supportsKinematic(Integrator integrator) { return entry(integrator).kinematic; }

bool supportsDynamic(Integrator integrator) { return entry(integrator).dynamic; }

int declaredOrder(Integrator integrator, Model model) {
  const auto& e = entry(integrator);
  return model == Model::Dynamic ? e.dynamic_order : e.kinematic_order;
}

std::string integratorNames() {
  std::string names;
  for (const auto& e : kIntegrators) {
    if (!names.empty()) names += ' ';
    names += e.name;
  }
  return names;
}

}  // namespace attitude_propagator
