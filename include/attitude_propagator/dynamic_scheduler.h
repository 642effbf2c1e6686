// The dynamic model behind the engine (docs/design.md §5.3): a DynamicPropagator, the queue of
// inputs stamped ahead of the clock and the publish grid, within the budgets of a call. An
// input stamped after the propagator's time waits until the grid reaches its stamp, so the
// state at a grid stamp includes exactly the inputs stamped up to it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "attitude_propagator/dynamic_propagator.h"
#include "attitude_propagator/propagator.h"
#include "attitude_propagator/publish_grid.h"

namespace attitude_propagator {

class DynamicScheduler final : public Propagator {
 public:
  /// Throws std::invalid_argument (from DynamicPropagator) for an invalid configuration, or
  /// when `config` has no dynamic configuration.
  DynamicScheduler(const EngineConfig& config, PropagatorHost& host);

  void submit(const Input& input) override;
  void publishDue(bool skip_intermediate) override;
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B) override;
  void reset() override;
  bool restartInputOrder(Source source) override;
  void reconfigure(const EngineConfig& next) override;

  EngineState state() const override;
  std::size_t pending() const override { return pending_.size(); }
  Model model() const override { return Model::Dynamic; }
  const std::string& modelName() const override { return model_name_; }
  Integrator integrator() const override { return dynamic_.integrator(); }
  double energyDrift() const override { return dynamic_.energyDrift(); }
  double momentumDrift() const override { return dynamic_.momentumDrift(); }

  std::optional<double> savedTime() const override;
  void save(ModelSnapshot& into) const override;
  void restore(const ModelSnapshot& from) override;
  bool advanceForFix(double t) override;
  void correctOrientation(const Eigen::Quaterniond& q_WB) override {
    dynamic_.correctOrientation(q_WB);
  }
  void replay(const ModelStep& step) override;

 private:
  void applyDynamic(const Input& input);
  /// The input to the propagator (setTorque or setRate), the held torque kept.
  StampOutcome applyToModel(const Input& input);
  void applyPendingUpTo(Stamp stamp);
  void publishGridStamp(Stamp stamp);

  PropagatorHost& host_;
  DynamicPropagator dynamic_;
  std::string model_name_;
  double publish_rate_;               // states at multiples of 1/publish_rate
  std::size_t max_pending_;           // inputs waiting at most
  std::size_t grid_budget_;           // grid stamps per call at most
  std::uint64_t work_budget_;         // integrator work per call at most
  std::vector<Input> pending_;        // sorted by stamp
  std::optional<Input> held_torque_;  // the last torque applied, for reconfigure()
};

}  // namespace attitude_propagator
