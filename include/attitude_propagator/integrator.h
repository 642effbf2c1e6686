// Names of the models and integrators (DESIGN §4). The names are part of the public interface:
// they are the values of the `model` and `integrator` parameters and appear in AttitudeState.
#pragma once

#include <string>

namespace attitude_propagator {

enum class Model { Auto, Kinematic, Dynamic };

enum class Integrator {
  Auto,
  Euler,             // kinematic, order 1
  Rk4,               // kinematic (order 2 from samples) and dynamic (order 4)
  Exp,               // kinematic, exact for constant rate
  Exp2,              // kinematic, order 2
  Cf4,               // kinematic, order 4
  ImplicitMidpoint,  // dynamic, order 2, keeps E and |M|
  Splitting,         // dynamic, order 2, Strang splitting of the free rotor
  Splitting4,        // dynamic, order 4, Yoshida composition of Splitting
  Dopri5,            // dynamic, adaptive 5(4)
  Exact,             // dynamic, torque-free closed form
};

/// Parses a `model` parameter value; throws std::invalid_argument naming the accepted values.
Model modelFromName(const std::string& name);
std::string modelName(Model model);

/// Parses an `integrator` parameter value; throws std::invalid_argument naming the accepted
/// values.
Integrator integratorFromName(const std::string& name);
std::string integratorName(Integrator integrator);

/// Whether the integrator can drive the given (resolved) model.
bool supportsKinematic(Integrator integrator);
bool supportsDynamic(Integrator integrator);

/// Declared order of convergence of a fixed-step method on smooth input (kinematic methods:
/// from rate samples; dynamic: on the Euler equations). 0 for Auto, Dopri5 (adaptive) and
/// Exact. Tests measure the order from results and compare with this.
int declaredOrder(Integrator integrator, Model model);

/// Space-separated list of all integrator names, for error messages.
std::string integratorNames();

}  // namespace attitude_propagator
