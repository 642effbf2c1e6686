// The model behind the engine: one interface, Propagator, implemented by the kinematic model
// (KinematicModel, kinematic_model.h) and the dynamic one (DynamicScheduler,
// dynamic_scheduler.h), and the types an input, a state and a call's result travel in. The
// engine judges an input against its source and the clock, subtracts the bias and moves rate
// stamps by rate_delay; what the input then does to the state, when a state is published and at
// which stamp, is the model's, which returns it from each call (ModelResult) for the engine to
// count, publish and keep. See docs/design.md §2 and §5.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include <Eigen/Geometry>

#include "attitude_propagator/models/counters.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/time/source_timeline.h"
#include "attitude_propagator/time/time_base.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

struct EngineConfig;

/// Where an input came from; chooses what it means. The core names no topic: the message layer
/// does (inputTopicName, input_decoders.h).
enum class Source { Imu, Twist, Torque };

/// A decoded input: a body rate w_B (rad/s) from Imu or Twist, or a torque (N m) in `frame`.
struct Input {
  Source source = Source::Imu;
  Stamp stamp = 0;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  TorqueFrame frame = TorqueFrame::Body;
  /// Rate noise covariance in the body frame (rad²/s²); zero: the configured default.
  Eigen::Matrix3d rate_covariance_B = Eigen::Matrix3d::Zero();
  /// Carried through untouched and handed back with the applied input (the node keeps the
  /// IMU message here, to republish it with the orientation at its stamp).
  std::shared_ptr<const void> payload;
};

/// What moved a model's state: kept in the fix history and repeated by a replay of a late fix
/// (docs/design.md §6.9). An input handed to the model, or (dynamic model) its advance to a
/// grid stamp, `input.stamp`.
struct ModelStep {
  Input input;
  bool advance = false;
};

/// The dynamic model's whole state for a replay: the propagator (knots, grid, held torque) and
/// the torque sample it holds. Inputs still waiting for the clock are not part of it: they
/// have not acted yet.
struct DynamicReplayState {
  DynamicPropagator dynamic;
  std::optional<Input> held_torque;
};

/// A model's whole state, saved after each step while fixes are on (plain values, copied into
/// reused slots): the kinematic propagator, or the dynamic one.
using ModelSnapshot = std::variant<std::monostate, KinematicPropagator, DynamicReplayState>;

/// The state to publish at a stamp.
struct EngineState {
  Stamp stamp = 0;
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();
  Eigen::Matrix3d P_B = Eigen::Matrix3d::Zero();  ///< orientation error covariance, body frame
  double norm_error = 0.0;
  std::uint64_t steps = 0;
  // Dynamic model only (zero in the kinematic model).
  Eigen::Vector3d M_B = Eigen::Vector3d::Zero();  ///< angular momentum, body frame
  double kinetic_energy = 0.0;
  /// estimate_gyro_bias (kinematic model): the estimated gyro bias (rad/s, body frame),
  /// subtracted from the rates on top of the configured one, and its standard deviation per
  /// axis; zero when the bias is not estimated (docs/design.md §6.9).
  Eigen::Vector3d gyro_bias_estimate_B = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias_stddev_B = Eigen::Vector3d::Zero();
};

/// Something the node should log (throttled per kind).
struct EngineNote {
  enum Kind {
    Gap,               ///< an input or the clock moved on by more than max_dt: state held
    StampsJumpedBack,  ///< a source's stamps went back by more than the threshold, and persisted
    Future,            ///< an input stamped more than max_future ahead of the clock: refused
    ClockJumpedBack,   ///< ROS time went back by more than the threshold: reset
    /// ROS time takes turns between two timelines (ClockTimeline): the later one followed, no
    /// reset; stamp: the tick of the other timeline.
    ClockTwoTimelines,
    Stale,
    NonFinite,
    OutOfRange,
    FailedStep,
    PendingFull,
    Deferred,
    HeldAhead,  ///< an input further ahead of the clock than its source's others: dropped
    /// The rates' stamps stopped fitting the stamp filter's model (SensorClockFilter::misfit()):
    /// their receipt stamps are used until they fit again.
    StampFilterMisfit,
  };
  Kind kind = Gap;
  std::optional<Source> source;  ///< empty: the clock
  Stamp stamp = 0;
  /// StampFilterMisfit: the stamps' jitter and the sensor period the filter measured (s).
  double jitter = 0.0, period = 0.0;
};

/// What one call of a model did (Propagator::submit, nextDue, replay), returned for the engine
/// to act on once the call is over, in this order: the model's counts and note; the outcome
/// counted and noted (a gap far from the origin re-pins the state there); where the state holds
/// at `stamp`, the covariance followed, the state published and the input handed on; the step
/// kept for late fixes. The model never calls the engine: what it needs of it (core time, the
/// clock, the last published stamp) it is given.
struct ModelResult {
  /// The outcome at `stamp` of the input (`source`) or of the advance to a grid stamp (source
  /// empty); empty when nothing moved the state (an input that waits, a grid stamp an input
  /// already brought the state to).
  std::optional<StampOutcome> outcome;
  std::optional<Source> source;
  Stamp stamp = 0;
  /// The state at `stamp` is published (kinematic: every input's; dynamic: a grid stamp's).
  bool publish = false;
  /// The input is handed on with the state at `stamp` (or `at`): it acted and the state holds.
  bool hand_on = false;
  /// The orientation covariance: unchanged, propagated over the step (h, w_step, the input's
  /// rate covariance; zero: the configured one), or back to the initial one (an anchor).
  enum class Covariance { Unchanged, Step, Anchor };
  Covariance covariance = Covariance::Unchanged;
  double h = 0.0;
  Eigen::Vector3d w_step = Eigen::Vector3d::Zero();
  /// The input that acted. Points into the call's argument or the model, valid until the
  /// model's next call.
  const Input* input = nullptr;
  /// The state the input took effect at, when not the model's newest (an input placed before
  /// the model's time: the state at its own stamp).
  std::optional<DynamicState> at;
  /// The step is kept for late fixes: the input that acted (the engine keeps an input it
  /// submitted as it received it, before the bias estimate), or with no input the advance to
  /// the grid stamp `stamp`.
  bool keep_step = false;
  /// Counts of the model's own, added to EngineCounters' fields of the same names.
  std::uint64_t late = 0, pending_overflow = 0, deferred_ticks = 0;
  /// A note of the model's own (StampFilterMisfit, PendingFull, Deferred).
  std::optional<EngineNote> note;
};

/// A model: what an input does to the state and when states are published, returned from each
/// call. Every call but setState and reconfigure never throws. What only a model with a clock of
/// its own means (a queue, a grid, invariants, moving on between steps) has a default that is the
/// kinematic model's: nothing waits, nothing is due, nothing drifts.
class Propagator {
 public:
  virtual ~Propagator() = default;

  /// An input in order for its source, not ahead of the clock by more than max_future, bias
  /// subtracted, rate stamps moved by rate_delay; `clock` the latest ROS time seen (empty before
  /// the first). Kinematic: integrated now, the state at its stamp published. Dynamic: applied
  /// when the clock reaches its stamp (at once when the propagator has already passed it); an
  /// input that waits comes back from nextDue when it acts. The result's input is set when it
  /// acted now, whatever became of it.
  virtual ModelResult submit(const Input& input, std::optional<Stamp> clock) = 0;
  /// The stamp at which the model starts core time from the clock alone, with no input yet
  /// (dynamic: the newest grid stamp at or before the clock); empty: the first input starts it.
  virtual std::optional<Stamp> firstStampFromClock(Stamp /*clock*/) const { return std::nullopt; }
  /// Starts a pass over what is due up to `clock` (the dynamic model's grid stamps, within the
  /// budgets of one pass; skip_intermediate: only the newest, the clock jumped by a gap). The
  /// engine then calls nextDue until it returns nothing, acting on each result before the next
  /// call. Kinematic: nothing is ever due (its states follow the inputs).
  virtual void beginDue(Stamp /*clock*/, std::optional<Stamp> /*last_published*/,
                        bool /*skip_intermediate*/) {}
  /// The next unit of the pass: one waiting input that acts, or one grid stamp reached (or
  /// deferred: the budget spent, the rest on the next pass); empty when the pass is over.
  /// `last_published`: the stamp of the last state published, as the engine knows it now.
  virtual std::optional<ModelResult> nextDue(std::optional<Stamp> /*last_published*/) {
    return std::nullopt;
  }

  /// Pins the state at core time t (a new anchor). Throws std::invalid_argument, leaving the
  /// state unchanged, for a state the propagator refuses.
  virtual void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B) = 0;
  /// Back to the initial state, waiting for an anchor; returns the queued inputs it dropped
  /// (the engine counts them, dropped_on_reset).
  virtual std::size_t reset() = 0;
  /// What a model did when a source's stamps went back and persisted.
  struct InputOrderRestart {
    /// The model's time is the inputs' (kinematic): the engine starts time again, from the
    /// initial state. Otherwise the model goes on, the source's inputs acting late.
    bool time_restarts = false;
    /// Queued inputs of the source's old timeline dropped (the engine counts them stale).
    std::size_t dropped = 0;
  };
  virtual InputOrderRestart restartInputOrder(Source source) = 0;
  /// A new propagator from `next` (same model), started from the current state at the current
  /// time; queued inputs and a held torque stay. Throws std::invalid_argument, leaving
  /// everything unchanged, when `next` is refused.
  virtual void reconfigure(const EngineConfig& next) = 0;

  /// The state at the propagator's newest stamp (stamp and P_B left to the engine).
  virtual EngineState state() const = 0;
  /// Inputs waiting for the clock (dynamic model).
  virtual std::size_t pending() const { return 0; }
  virtual Model model() const = 0;
  /// "kinematic" or the dynamic propagator's model name.
  virtual const std::string& modelName() const = 0;
  virtual Integrator integrator() const = 0;
  /// Relative drifts of energy and |M| since the anchor (dynamic model; 0 otherwise).
  virtual double energyDrift() const { return 0.0; }
  virtual double momentumDrift() const { return 0.0; }
  /// True when the model gives each of several rate samples stamped alike its own stamp (the
  /// sensor-clock filter's FIFO reads): the engine then lets a repeated stamp through.
  virtual bool takesRepeatedRateStamps() const { return false; }
  /// The kinematic propagator, for its diagnostics; nullptr in the dynamic model.
  virtual const KinematicPropagator* kinematic() const { return nullptr; }

  // Late fixes (docs/design.md §6.9): the engine saves the model after each step, sets it back
  // to a saved state, corrects it there and repeats the steps since.
  /// The model's core time when it has a state to save (anchored); empty otherwise.
  virtual std::optional<double> savedTime() const = 0;
  /// Saves the whole state into `into` (reusing its storage when it holds this model's).
  virtual void save(ModelSnapshot& into) const = 0;
  /// Back to a state saved by this model (a snapshot of another kind is ignored).
  virtual void restore(const ModelSnapshot& from) = 0;
  /// Moves a restored model on to core time t, short of its next saved step, so that a fix
  /// stamped there acts at its own stamp. False when the model moves only by its steps
  /// (kinematic: a step needs the next sample; the fix is then carried back to the model's
  /// time along the geodesic).
  virtual bool advanceForFix(double /*t*/) { return false; }
  /// Replaces the orientation at the model's time; everything else (the rate, the sample
  /// window, the knots and grid, the held torque) stays.
  virtual void correctOrientation(const Eigen::Quaterniond& q_WB) = 0;
  /// Repeats a saved step in a replay, and returns what it did as the live call would.
  /// FixReplay keeps only the covariance of the result: nothing is counted, noted, kept or
  /// published again.
  virtual ModelResult replay(const ModelStep& step) = 0;
};

/// The time policy of the model `config` asks for.
const TimePolicy& timePolicyOf(const EngineConfig& config);

/// Makes the model an engine drives (on the engine's time base): makePropagator, or a model of
/// a test's own.
using PropagatorFactory =
    std::function<std::unique_ptr<Propagator>(const EngineConfig&, const TimeBase&)>;

/// The model `config` asks for. Throws std::invalid_argument (from the propagators) for an
/// invalid configuration.
std::unique_ptr<Propagator> makePropagator(const EngineConfig& config, const TimeBase& time);

}  // namespace attitude_propagator
