// The kinematic model behind the engine: a KinematicPropagator whose rate inputs stamp the
// states. Each input is integrated when it arrives and the state at its stamp (or where the
// stamp filter or the average's stamp put it) is published; the orientation covariance follows
// each step.
#pragma once

#include <string>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/models/propagator.h"

namespace attitude_propagator {

class KinematicModel final : public Propagator {
 public:
  /// Throws std::invalid_argument (from KinematicPropagator) for an invalid configuration.
  KinematicModel(const EngineConfig& config, const TimeBase& time);

  ModelResult submit(const Input& input, std::optional<Stamp> clock) override;
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B) override {
    kinematic_.setState(t, q_WB, w_B);
  }
  std::size_t reset() override {
    kinematic_.reset();
    return 0;  // nothing waits
  }
  InputOrderRestart restartInputOrder(Source source) override;
  void reconfigure(const EngineConfig& next) override;

  EngineState state() const override;
  Model model() const override { return Model::Kinematic; }
  bool takesRepeatedRateStamps() const override { return kinematic_.stampFilter() != nullptr; }
  const std::string& modelName() const override { return model_name_; }
  Integrator integrator() const override { return kinematic_.integrator(); }
  const KinematicPropagator* kinematic() const override { return &kinematic_; }

  std::optional<double> savedTime() const override;
  void save(ModelSnapshot& into) const override { into = kinematic_; }
  void restore(const ModelSnapshot& from) override;
  void correctOrientation(const Eigen::Quaterniond& q_WB) override {
    kinematic_.correctOrientation(q_WB);
  }
  ModelResult replay(const ModelStep& step) override;

 private:
  /// What one input did to the propagator: the outcome, the step's length and rotation rate,
  /// and whether the stamp filter stopped fitting.
  struct Step {
    StampOutcome outcome = StampOutcome::Waiting;
    double h = 0.0;
    Eigen::Vector3d w_step = Eigen::Vector3d::Zero();
    bool misfit = false;
  };
  /// One input through the propagator, nothing else.
  Step step(const Input& input);
  /// The orientation covariance over the step, or back to the initial one at an anchor.
  static void followCovariance(const Step& step, ModelResult& result);

  const TimeBase& time_;
  KinematicPropagator kinematic_;
  std::string model_name_ = "kinematic";
};

}  // namespace attitude_propagator
