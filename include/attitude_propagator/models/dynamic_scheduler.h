// The dynamic model behind the engine (docs/design.md §5.3): a DynamicPropagator, the queue of
// inputs stamped ahead of the clock and the publish grid, within the budgets of a call. An
// input stamped after the propagator's time waits until the grid reaches its stamp, so the
// state at a grid stamp includes exactly the inputs stamped up to it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/propagator.h"
#include "attitude_propagator/time/publish_grid.h"

namespace attitude_propagator {

class DynamicScheduler final : public Propagator {
 public:
  /// Throws std::invalid_argument (from DynamicPropagator) for an invalid configuration, or
  /// when `config` has no dynamic configuration.
  DynamicScheduler(const EngineConfig& config, const TimeBase& time);

  ModelResult submit(const Input& input, std::optional<Stamp> clock) override;
  std::optional<Stamp> firstStampFromClock(Stamp clock) const override;
  void beginDue(Stamp clock, std::optional<Stamp> last_published, bool skip_intermediate) override;
  std::optional<ModelResult> nextDue(std::optional<Stamp> last_published) override;
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B) override;
  std::size_t reset() override;
  InputOrderRestart restartInputOrder(Source source) override;
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
    recent_.clear();  // the states before it are no longer the estimate's
  }
  ModelResult replay(const ModelStep& step) override;

 private:
  /// An input acting now: at once, or when the grid reached its stamp.
  ModelResult applyDynamic(const Input& input);
  /// The input to the propagator (setTorque or setRate), the held torque kept.
  StampOutcome applyToModel(const Input& input);
  /// Moves the waiting inputs stamped up to `stamp` to the ones due in this pass.
  void takeDueUpTo(Stamp stamp);
  /// The grid stamp reached: the advance to it and its state published; empty when nothing is
  /// published there (already published, or set_state pinned a later time).
  std::optional<ModelResult> publishGridStamp(Stamp stamp, std::optional<Stamp> last_published);

  /// A pass over the grid stamps due (beginDue, nextDue): the stamps k to k_now, and what the
  /// pass has spent of its budgets.
  struct Pass {
    bool open = false;
    std::int64_t k = 0, k_now = -1;
    bool at_grid_stamp = false;  // the inputs due at gridStamp(k) are being applied
    Stamp stamp = 0;             // gridStamp(k), once at_grid_stamp
    std::size_t handled = 0;     // grid stamps begun
    std::uint64_t work = 0;      // integrator work
  };

  /// The states at the newest grid stamps, so that a late input (placed at the last grid point)
  /// is handed on with the state at its own stamp: interpolated between the two grid states
  /// around it, along the geodesic (exact for a constant rate). Empty after a reset, a pinned
  /// state, a reconfiguration or a fix.
  class RecentStates {
   public:
    void push(double t, const DynamicState& state);
    void clear() { size_ = 0; }
    /// The state at t, or empty when t is not between two states kept.
    std::optional<DynamicState> at(double t) const;

   private:
    static constexpr std::size_t kKept = 64;
    struct Entry {
      double t = 0.0;
      DynamicState state;
    };
    const Entry& entry(std::size_t i) const { return ring_[(head_ + i) % kKept]; }
    std::array<Entry, kKept> ring_{};
    std::size_t head_ = 0;
    std::size_t size_ = 0;
  };

  const TimeBase& time_;
  DynamicPropagator dynamic_;
  std::string model_name_;
  double publish_rate_;         // states at multiples of 1/publish_rate
  std::size_t max_pending_;     // inputs waiting at most
  std::size_t grid_budget_;     // grid stamps per call at most
  std::uint64_t work_budget_;   // integrator work per call at most
  std::vector<Input> pending_;  // sorted by stamp
  std::deque<Input> due_;       // taken from pending_ for the pass's grid stamp, in order
  Input acting_;                // the due input last applied (a result points to it)
  Pass pass_;
  std::optional<Input> held_torque_;  // the last torque applied, for reconfigure()
  RecentStates recent_;
};

}  // namespace attitude_propagator
