// A model of a test's own around the kinematic model (Propagator, models/propagator.h): every
// call passes through to it, and a test overrides the calls it watches or replaces. factoryOf
// builds one into an engine (AttitudeEngine's PropagatorFactory) and points the test at it.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "attitude_propagator/models/kinematic_model.h"

namespace wrapped_model {

namespace ap = attitude_propagator;

class WrappedKinematicModel : public ap::Propagator {
 public:
  WrappedKinematicModel(const ap::EngineConfig& config, const ap::TimeBase& time)
      : inner_(config, time) {}

  ap::ModelResult submit(const ap::Input& input, std::optional<ap::Stamp> clock) override {
    return inner_.submit(input, clock);
  }
  std::optional<ap::Stamp> firstStampFromClock(ap::Stamp clock) const override {
    return inner_.firstStampFromClock(clock);
  }
  void beginDue(ap::Stamp clock, std::optional<ap::Stamp> last_published,
                bool skip_intermediate) override {
    inner_.beginDue(clock, last_published, skip_intermediate);
  }
  std::optional<ap::ModelResult> nextDue(std::optional<ap::Stamp> last_published) override {
    return inner_.nextDue(last_published);
  }
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B) override {
    inner_.setState(t, q_WB, w_B);
  }
  std::size_t reset() override { return inner_.reset(); }
  InputOrderRestart restartInputOrder(ap::Source source) override {
    return inner_.restartInputOrder(source);
  }
  void reconfigure(const ap::EngineConfig& next) override { inner_.reconfigure(next); }
  ap::EngineState state() const override { return inner_.state(); }
  ap::Model model() const override { return inner_.model(); }
  const std::string& modelName() const override { return inner_.modelName(); }
  ap::Integrator integrator() const override { return inner_.integrator(); }
  bool takesRepeatedRateStamps() const override { return inner_.takesRepeatedRateStamps(); }
  const ap::KinematicPropagator* kinematic() const override { return inner_.kinematic(); }
  std::optional<double> savedTime() const override { return inner_.savedTime(); }
  void save(ap::ModelSnapshot& into) const override { inner_.save(into); }
  void restore(const ap::ModelSnapshot& from) override { inner_.restore(from); }
  void correctOrientation(const Eigen::Quaterniond& q_WB) override {
    inner_.correctOrientation(q_WB);
  }
  ap::ModelResult replay(const ap::ModelStep& step) override { return inner_.replay(step); }

 protected:
  ap::KinematicModel inner_;
};

/// Makes a `Model` (built from the configuration and the engine's time base) for the engine,
/// and points `made` at it.
template <class Model>
ap::PropagatorFactory factoryOf(Model*& made) {
  return [&made](const ap::EngineConfig& config, const ap::TimeBase& time) {
    auto model = std::make_unique<Model>(config, time);
    made = model.get();
    return std::unique_ptr<ap::Propagator>(std::move(model));
  };
}

}  // namespace wrapped_model
