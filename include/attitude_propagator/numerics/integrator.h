// Names of the models and integrators (docs/design.md §4). The names are part of the public
// interface: they are the values of the `model` and `integrator` parameters and appear in
// AttitudeState.
//
// The integrators are one table (src/core/numerics/integrator.cpp), one row per method
// (IntegratorInfo below): its name, the models it drives with their declared orders, the rate
// samples it reads, what it keeps exactly, and its step function. Names, error messages, the
// parameter documentation, the choice of `auto`, the tests' method lists and order bounds, the
// benchmarks, evaluate_bag_core's methods and the fuzz codes all read the table; outside C++ the
// reconfigure enum and the fuzz seeds read its source, the bag tools' scripts and charts its
// methods through evaluate_bag_core (test/checks/integrator_lists.sh checks each against the
// built table). Adding an integrator: an enumerator below, a step function, its declaration and
// a row appended in integrator.cpp (docs/design.md §4.2).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace attitude_propagator {

enum class Model { Auto, Kinematic, Dynamic };

/// In the table's order (integrator.cpp checks it). A new method is appended at the end, never
/// inserted: a row's index is also its fuzz targets' code and its place in the reconfigure enum.
enum class Integrator {
  Auto,
  Euler,
  Rk4,
  Exp,
  Exp2,
  Cf4,
  ImplicitMidpoint,
  Splitting,
  Splitting4,
  Dopri5,
  Exact,
};

class RateWindow;        // kinematic_step.h
enum class RateSamples;  // kinematic_step.h
class DynamicStepper;    // dynamic_step.h
struct PrincipalState;   // dynamic_step.h
struct PrincipalTorque;  // dynamic_step.h
struct StepInfo;         // dynamic_step.h
enum class StepStatus;   // dynamic_step.h

/// A kinematic step: q_WB advanced across the window's interval [i, i + 1], returned before
/// renormalisation (kinematic_step.h).
using KinematicStepFunction = Eigen::Quaterniond (*)(const Eigen::Quaterniond& q_WB,
                                                     const RateWindow& window, std::size_t i,
                                                     RateSamples kind);

/// A dynamic step: x advanced by h in place, in the principal frame, within `budget` work units
/// (dynamic_step.h, DynamicStepper).
using DynamicStepFunction = StepStatus (DynamicStepper::*)(PrincipalState& x,
                                                           const PrincipalTorque& torque, double h,
                                                           std::uint64_t budget,
                                                           StepInfo& info) const;

/// What a method keeps exactly (to round-off) besides converging at its order; or-ed flags.
namespace keeps {
constexpr unsigned kNothing = 0;
constexpr unsigned kUnitNorm = 1u << 0;      ///< |q| = 1 after every step, before renormalising
constexpr unsigned kConstantRate = 1u << 1;  ///< a constant body rate, at any step
constexpr unsigned kEnergy = 1u << 2;        ///< a free body's kinetic energy
constexpr unsigned kMomentum = 1u << 3;      ///< a free body's |M|
constexpr unsigned kExactFlow = 1u << 4;     ///< the exact solution: any step length, no grid
}  // namespace keeps

/// Where `auto` picks the method; or-ed flags.
namespace auto_for {
constexpr unsigned kNever = 0;
constexpr unsigned kKinematic = 1u << 0;
constexpr unsigned kTorqueFree = 1u << 1;  ///< dynamic model without torque input
constexpr unsigned kTorqued = 1u << 2;     ///< dynamic model with torque input
}  // namespace auto_for

/// One row of the table: a method's name and what it is. integrator.cpp builds each row field by
/// field, naming only the fields that differ from these defaults (a method with no declared
/// order, reading no samples, keeping nothing, never picked by `auto`, taking no torque, driving
/// no model).
struct IntegratorInfo {
  Integrator id = Integrator::Auto;
  /// The parameter value: lower case, digits and '_'.
  const char* name = "";
  /// One line for the reconfigure enum's choice (cfg/AttitudePropagator.cfg reads it).
  const char* summary = "";
  /// Declared orders of convergence on smooth input; 0 where the method has no fixed order
  /// (adaptive, exact) or does not drive the model. Tests measure them.
  int kinematic_order = 0;  ///< from instantaneous rate samples
  int averaged_order = 0;   ///< from interval-averaged rate samples
  int dynamic_order = 0;    ///< on the Euler equations
  /// Kinematic: the rate samples a step reads at most, the newest last (the window it needs;
  /// at most RateWindow::kCapacity, which integrator.cpp checks).
  int samples = 0;
  unsigned keeps = keeps::kNothing;      ///< keeps::*
  unsigned auto_for = auto_for::kNever;  ///< auto_for::*
  /// Dynamic: whether a torque may act (the exact solution is torque-free).
  bool takes_torque = false;
  /// Kinematic start-up: until `samples` samples exist after an anchor the step runs on the
  /// fewer it has; when the window first fills, the propagator integrates again from the
  /// anchor across it, so the start-up leaves no lower-order error in the states that follow.
  bool restart_from_anchor = false;
  /// The step functions; which are set says which models the method drives.
  KinematicStepFunction kinematic_step = nullptr;  ///< nullptr: not a kinematic method
  DynamicStepFunction dynamic_step = nullptr;      ///< nullptr: not a dynamic method
};

/// Every row, `auto` first, in the enumeration's order.
const std::vector<IntegratorInfo>& integratorTable();
const IntegratorInfo& integratorInfo(Integrator integrator);

/// Parses a `model` parameter value; throws std::invalid_argument naming the accepted values.
Model modelFromName(const std::string& name);
std::string modelName(Model model);

/// Parses an `integrator` parameter value; throws std::invalid_argument naming the accepted
/// values.
Integrator integratorFromName(const std::string& name);
/// The same for a program of one model (Kinematic or Dynamic): a method that does not drive it
/// is refused too, and the accepted values named are auto and the model's (integratorsFor).
Integrator integratorFromName(const std::string& name, Model model);
std::string integratorName(Integrator integrator);

/// Whether the integrator can drive the given (resolved) model; Auto drives both.
bool supportsKinematic(Integrator integrator);
bool supportsDynamic(Integrator integrator);

/// Declared order of convergence of a fixed-step method on smooth input (kinematic methods:
/// from instantaneous rate samples; dynamic: on the Euler equations). 0 for Auto, Dopri5
/// (adaptive) and Exact. Tests measure the order from results and compare with this.
int declaredOrder(Integrator integrator, Model model);

/// The methods that drive `model` (Kinematic or Dynamic), in the table's order, without Auto.
std::vector<Integrator> integratorsFor(Model model);

/// What `auto` resolves to for a model (Kinematic or Dynamic) with or without torque input. On
/// the kinematic model that is the starting method: KinematicAutoRule (auto_integrator.h) may
/// step with exp2 or rk4 where the stream calls for it (docs/real_streams.md).
Integrator autoIntegrator(Model model, bool torque_input);

/// Every integrator name, `auto` first; or the names of the given integrators.
std::vector<std::string> integratorNames();
std::vector<std::string> integratorNames(const std::vector<Integrator>& integrators);

/// Names joined by single spaces, for messages ("accepted: euler rk4 ...").
std::string joinNames(const std::vector<std::string>& names);

}  // namespace attitude_propagator
