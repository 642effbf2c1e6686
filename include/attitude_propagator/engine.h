// The propagation engine: everything between a decoded input and a state to publish, with no
// ROS in it. It owns the model (one Propagator, propagator.h: kinematic, or dynamic with its
// queue of inputs stamped ahead of the clock and its publish grid), the time origin, the
// orientation covariance, the gyro bias, the time policy (each source's stamps judged against its
// own: a straggler is dropped, a backward jump is recognised when it persists; an input too far
// ahead of the clock is refused; a clock that jumps back resets, one that jumps ahead is a gap) and
// the counters shown in diagnostics. The node decodes messages,
// submits them here, tells the engine what time it is, and publishes what the engine hands to
// its sink. See docs/design.md for the data flow.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/aiding.h"
#include "attitude_propagator/estimation/error_state.h"
#include "attitude_propagator/estimation/fix_replay.h"
#include "attitude_propagator/estimation/hard_iron_fit.h"
#include "attitude_propagator/estimation/magnetic_heading.h"
#include "attitude_propagator/estimation/measurement.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/models/outcome_table.h"
#include "attitude_propagator/models/propagator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/time/input_order.h"
#include "attitude_propagator/time/source_timeline.h"
#include "attitude_propagator/time/stamp_queue.h"

namespace attitude_propagator {

/// Receives what the engine produces. Called synchronously from the engine's methods.
class EngineSink {
 public:
  virtual ~EngineSink() = default;
  /// A new state, at most once per stamp and with stamps increasing (until a reset).
  virtual void publishState(const EngineState& state) = 0;
  /// An input was applied; `state` is the state at its stamp (or where it took effect).
  virtual void inputApplied(const Input& input, const EngineState& state) = 0;
  virtual void note(const EngineNote& note) = 0;
};

/// Inputs arriving on average more than this many seconds away from the clock (behind, or
/// ahead) deserve a warning: tf listeners looking up "now" will not find the transforms, and in
/// the dynamic model each input acts late. A sensor clock skewed from the node's, or a
/// transport that queues.
constexpr double kInputLagWarning = 0.5;

class AttitudeEngine : private StepCovariance {
 public:
  /// Throws std::invalid_argument (from the propagators) for an invalid configuration.
  AttitudeEngine(const EngineConfig& config, EngineSink& sink);
  /// The same, driving the model `make` makes (a test's own, around a real one).
  AttitudeEngine(const EngineConfig& config, EngineSink& sink, const PropagatorFactory& make);
  ~AttitudeEngine();
  AttitudeEngine(const AttitudeEngine&) = delete;
  AttitudeEngine& operator=(const AttitudeEngine&) = delete;

  /// An input. Judged first against its own source (SourceTimeline): a straggler is dropped,
  /// a persistent backward jump starts the source's time again (kinematic model: the initial
  /// state, and the outputs' stamps start again; dynamic model: the source's inputs go on, late),
  /// and one stamped more than max_future ahead of a known clock is refused. Kinematic model:
  /// integrated now, and the state at its stamp published. Dynamic model: applied when the
  /// clock reaches its stamp (at once, where the model can still change, when the propagator
  /// has already passed it). Never throws.
  void submit(const Input& input);

  /// An input the node turned away (counted).
  void reject(Rejection why);

  /// A gyro bias (rad/s, body frame) in force for rate inputs stamped at or after
  /// `stamp`; subtracted before integration. False (counted rejected_bias) when non-finite,
  /// larger than the largest accepted body rate or stamped more than max_future ahead of a
  /// known clock; false (counted bias_queue_full) when 64 wait and it is stamped furthest
  /// ahead, else the furthest waiting one is dropped (counted): none takes effect before its
  /// stamp. The `gyro_bias` parameter is the bias before any sample.
  bool submitBias(Stamp stamp, const Eigen::Vector3d& gyro_bias_B);
  void rejectBias() { ++counters_.rejected_bias; }
  /// The bias subtracted from the latest rate input.
  const Eigen::Vector3d& gyroBias() const { return gyro_bias_B_; }
  /// The kinematic propagator (nullptr in the dynamic model), for its diagnostics.
  const KinematicPropagator* kinematic() const { return propagator_->kinematic(); }

  /// An absolute attitude q_WB measured at `stamp` (usually in the past), with the covariance
  /// (rad^2) of its rotation-vector error in the body frame, like P_B; all zero: fix_stddev^2 I.
  /// Applied at its stamp (fix_mode: fuse or reset) and the rate inputs since replayed, so the
  /// newest state is what it would have been had the fix arrived on time; the state is published
  /// with the next output. Both models (dynamic: the torques and rates since its stamp replayed,
  /// the angular velocity its own). Never throws. docs/design.md §6.9.
  FixOutcome submitFix(Stamp stamp, const Eigen::Quaterniond& q_WB,
                       const Eigen::Matrix3d& covariance_B);
  /// A specific force f_B (m/s^2, body frame, gravity included: REP-145) measured at `stamp`,
  /// with its covariance (m^2/s^4; all zero, or use_accel_covariance false: accel_stddev^2 I):
  /// a measurement of the gravity direction, counted in counters().accel. Stamped as the last
  /// IMU rate submitted (the same message, submitted after it), it acts where that rate took
  /// effect, whatever rate_delay or the stamp filter did to its stamp, and nothing is kept for
  /// it; otherwise at its stamp (moved back by rate_delay) like a fix (the rates since
  /// replayed). Off (ignored) without use_accel. Never throws. docs/design.md §6.10.
  AidingOutcome submitAcceleration(Stamp stamp, const Eigen::Vector3d& f_B,
                                   const Eigen::Matrix3d& covariance_B);
  /// A magnetic field read_B (tesla, body frame) measured at `stamp`, with its covariance (T^2;
  /// all zero, or use_mag_covariance false: mag_stddev^2 I): less mag_bias, a measurement of the
  /// heading alone, counted in counters().mag. Off (ignored) without use_mag. Never throws.
  AidingOutcome submitMagneticField(Stamp stamp, const Eigen::Vector3d& read_B,
                                    const Eigen::Matrix3d& covariance_B);
  /// use_mag: the sphere the field reads submitted lie on (HardIronFit), fitted to them as
  /// read (mag_bias not taken off: its centre is the mag_bias to give), whatever became of
  /// them after; every read since the engine was built, through resets and reconfigures (a
  /// read of the sensor's own field does not age with the clock).
  const HardIronFit& fieldFit() const { return field_fit_; }
  /// Gravity and field samples waiting for the rates to reach their stamps.
  std::size_t pendingMeasurements() const { return pending_measurements_.size(); }
  /// Whether the tilt is known: always, but with align before the first gravity sample.
  bool tiltKnown() const { return tilt_known_; }
  /// Fixes waiting for the rates to reach their stamps.
  std::size_t pendingFixes() const { return pending_fixes_.size(); }
  /// Rate inputs kept for late fixes (0 before the first fix).
  std::size_t fixHistorySize() const { return replay_.size(); }
  /// estimate_gyro_bias: the estimated bias (rad/s, body frame), subtracted on top of
  /// gyroBias(), and its standard deviation per axis; zero otherwise.
  const Eigen::Vector3d& gyroBiasEstimate() const { return error_.bias_B; }
  Eigen::Vector3d gyroBiasStddev() const;

  /// One tick of a complete clock record (every /clock message under sim time): a jump back
  /// by more than the threshold resets; a jump ahead by more than max_dt is a gap, so the grid
  /// stamps inside it are not published; otherwise every grid stamp up to `now` is. Two
  /// timelines taking turns (two /clock publishers) cost one reset at most: the later one is
  /// followed and the other's ticks are ignored until the clock settles (ClockTimeline).
  void clockTick(Stamp now);
  /// A look at the clock from a callback, where ticks may have been missed (wall time, or a
  /// timer that ran late): jumps back reset, but lateness is never a gap, and every grid
  /// stamp since the last one published is published (at most grid_budget per call).
  void poll(Stamp now);
  /// Publishes grid stamps left over by a call that ran out of budget, up to the last time
  /// seen; the clock itself is not read.
  void drain();
  /// The ticks that bring the clock from `last` (the previous tick; none: this is the first)
  /// to `now` where no clock record exists and the inputs' stamps drive the clock: steps of
  /// at most half grid_budget grid periods, so no grid stamp is ever deferred by the budget,
  /// and `now` last. A jump longer than max_dt, or not ahead, is the one tick `now` (a gap, or
  /// a jump back, as clockTick judges a clock record's). Defined in engine_clock_ticks.cpp.
  std::vector<Stamp> clockTicksTo(std::optional<Stamp> last, Stamp now) const;

  /// Live reconfiguration (same model): the rate noise, the time policy, the torque timeout
  /// and the integrator. A new propagator is built from `next` and started from the current
  /// state at the current time (a held torque stays in force); the past is not re-integrated.
  /// Returns an empty string, or why `next` was refused (then nothing changes).
  std::string reconfigure(const EngineConfig& next);

  /// Back to the initial state; the next input (or clock tick) anchors again. Queued inputs are
  /// dropped (counted); each source's order is kept, so a straggler stays a straggler.
  void reset();
  /// Pins the state at `stamp`. Returns an empty string, or why it was refused (a stamp more
  /// than max_future ahead of the clock, a state the propagator refuses).
  std::string setState(Stamp stamp, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B);

  const EngineCounters& counters() const { return counters_; }
  /// While ROS time takes turns between two timelines (two /clock publishers): the newest tick
  /// of the one not followed; empty otherwise (ClockTimeline).
  std::optional<Stamp> otherClock() const { return clock_line_.other(); }
  /// The ROS time followed; empty before the first look at the clock.
  std::optional<Stamp> clockNow() const { return clock_; }
  /// Core time: its origin, as the engine pinned it (docs/design.md §6.1).
  const TimeBase& timeBase() const { return time_; }
  /// The configuration in force (budgets, bounds), for callers that drive the clock.
  const EngineConfig& config() const { return config_; }
  /// Mean seconds by which the inputs of `source` arrive behind the clock (negative: ahead);
  /// empty before one arrived with a clock known.
  std::optional<double> inputLag(Source source) const;
  std::size_t pending() const { return propagator_->pending(); }
  bool dynamicModel() const { return propagator_->model() == Model::Dynamic; }
  /// "kinematic" or the dynamic propagator's model name.
  const std::string& modelName() const { return propagator_->modelName(); }
  Integrator integrator() const { return propagator_->integrator(); }
  /// The current state (at the propagator's own time).
  EngineState state() const;
  /// Relative drifts of energy and |M| since the anchor (dynamic model; 0 otherwise).
  double energyDrift() const { return propagator_->energyDrift(); }
  double momentumDrift() const { return propagator_->momentumDrift(); }

  /// The grid stamp with index k: round(k / publish_rate) in ns.
  Stamp gridStamp(std::int64_t k) const;
  /// The largest k with gridStamp(k) <= now.
  std::int64_t gridIndexAtOrBefore(Stamp now) const;

 private:
  double coreTime(Stamp stamp) const { return time_.coreTime(stamp); }
  std::optional<Stamp> stampAt(double t) const { return time_.stampAt(t); }

  // What a model's call did (ModelResult), acted on when the call is over.
  /// The result in its order: counts and note, outcome, covariance, the state published, the
  /// input handed on, the step kept (`received`: the input as the engine submitted it, before
  /// the bias estimate; null for what the model did on its own).
  void act(const ModelResult& result, const Input* received);
  /// Counts and notes an outcome (source empty: the clock); a gap far from the origin re-pins
  /// the state there (rebaseIfFar).
  void countOutcome(StampOutcome outcome, std::optional<Source> source, Stamp stamp);
  /// Publishes the state at `stamp` (once per stamp, increasing).
  void emitState(Stamp stamp);
  /// Hands an applied input on with the state at `stamp`, or `at` (an input placed before the
  /// model's time: the state at its own stamp, not the model's newest).
  void handOn(const Input& input, Stamp stamp, const std::optional<DynamicState>& at);
  /// The orientation covariance as the result says: over its step, or back to the initial one
  /// (live, and in a replay: StepCovariance).
  void followCovariance(const ModelResult& result) override;
  /// Propagated over a step of length h with the step's rate w_step and the input's rate
  /// covariance (zero: the configured one).
  void propagateCovariance(double h, const Eigen::Vector3d& w_step,
                           const Eigen::Matrix3d& rate_covariance_B);
  void anchorCovariance();
  /// Keeps the result's step for late fixes (keep_history_).
  void keepStep(const ModelResult& result, const Input* received);

  void rebaseIfFar(Stamp stamp);
  /// The grid stamps due up to the clock (dynamic model), then the fixes and measurements the
  /// model's time reached.
  void publishDue(bool skip_intermediate);
  /// Judges a look at the clock (ClockTimeline): a jump back resets, two timelines are counted
  /// and noted; clock_ follows. Returns the verdict.
  ClockTimeline::Verdict judgeClock(Stamp now);
  bool tooFarAhead(Stamp stamp) const;
  /// An input as submitted (after rate_delay) with the stamp it was received with (the bias's).
  struct ReceivedInput {
    Input input;
    Stamp received_stamp;
  };
  /// Judges an input against its source's order (InputOrder); false when it is not used now
  /// (dropped, or held in a run from an earlier time). When it completes a backward jump,
  /// `confirming` gets the inputs of the run before it, in order: they are used before it
  /// (docs/design.md §6.5).
  bool inOrder(const ReceivedInput& input, std::vector<ReceivedInput>& confirming);
  /// Counts and notes an input dropped as stale (a straggler, or held in a run that broke).
  void countStale(const ReceivedInput& dropped);
  void restartTimeline(Source source, Stamp stamp);
  /// Hands an input in order to the model: the bias in force subtracted, due fixes applied.
  void use(const ReceivedInput& received);
  void resetState(bool forget_time);
  Eigen::Matrix3d initialCovariance() const;
  EngineState stateAt(Stamp stamp) const;

  /// The bias in force at `stamp` (bias samples up to it take effect).
  const Eigen::Vector3d& biasAt(Stamp stamp);

  /// Hands a rate input to the model, the bias estimate subtracted.
  void submitToModel(const Input& input);
  /// Starts the fix history at the newest state, unless it is kept already.
  void keepHistory();
  /// Applies the waiting fixes (and gravity and field samples) the rates have reached.
  void applyDueFixes();
  /// A gravity or field sample on its way: the measurement and the value it was made from.
  struct PendingMeasurement {
    Stamp stamp;
    std::shared_ptr<const Measurement> measurement;
    Eigen::Vector3d value;
  };
  AidingOutcome placeMeasurement(PendingMeasurement pm);
  /// Applies a measurement to the newest state; with the history kept (`kept` then holds it),
  /// appends it as an entry of its own.
  AidingOutcome applyAtNewest(const Measurement& m, Stamp stamp, const Eigen::Vector3d& value,
                              std::shared_ptr<const Measurement> kept);
  AidingOutcome applyMeasurement(const PendingMeasurement& pm);
  /// Fuses, aligns to or recovers with a measurement at the attitude q and error state e of
  /// its stamp; `reset` says whether it was applied as a reset.
  AidingOutcome decideMeasurement(const Measurement& m, Stamp stamp, const Eigen::Vector3d& value,
                                  Eigen::Quaterniond& q, ErrorState& e, bool& reset);
  void applyDueMeasurements();
  AidingCounters& aidingCounters(MeasurementKind kind) {
    return kind == MeasurementKind::Gravity ? counters_.accel : counters_.mag;
  }
  void countFix(FixOutcome outcome);
  /// The bias prior: estimate zero, covariance gyro_bias_stddev^2 I, no cross terms.
  void resetBiasState();

  EngineConfig config_;
  EngineSink& sink_;
  TimeBase time_;  // core time: the origin (time_base.h); before the model, which reads it
  std::unique_ptr<Propagator> propagator_;
  Eigen::Matrix3d default_R_B_;
  ErrorState error_;  // P_B, and the bias estimate with its covariances
  Eigen::Vector3d gyro_bias_B_ = Eigen::Vector3d::Zero();
  StampQueue<Eigen::Vector3d> pending_gyro_bias_{kMaxPendingBias};  // stamped ahead of the rates

  std::optional<Stamp> last_published_;      // one state per stamp, increasing
  std::optional<Stamp> clock_;               // the ROS time followed (clock_line_)
  ClockTimeline clock_line_;                 // ROS time's own timeline(s)
  Stamp rate_delay_ns_ = 0;                  // config_.rate_delay
  InputOrder<ReceivedInput> order_rule_{3};  // per Source (Imu, Twist, Torque), its runs held
  EngineCounters counters_;

  // Fixes: whether the history is kept (from the first fix or late sample on), the history
  // with the replay of late corrections (FixReplay: after the model and the error state it
  // drives), and the fixes waiting for the rates.
  bool keep_history_ = false;
  FixReplay replay_;
  StampQueue<LateFix> pending_fixes_{kMaxPendingFixes};  // stamped ahead of the rates

  // Gravity and the magnetic field (docs/design.md §6.10).
  StampQueue<PendingMeasurement> pending_measurements_{kMaxPendingMeasurements};
  bool tilt_known_ = true;                  // false with align until the first gravity sample
  LinearAcceleration linear_acceleration_;  // seen lately in the gravity samples
  LinearVariance linear_variance_;          // its variances per axis (m^2/s^4), the newest
  TiltDisagreement tilt_disagreement_;      // the published tilt covariance's lasting share
  std::optional<Stamp> last_imu_stamp_;     // as received, of the last IMU rate the model took
  RejectionRun accel_run_;                  // the gate's rejections in a row, per kind
  RejectionRun mag_run_;
  MagneticReference mag_reference_;     // the field's magnitude and dip, learned
  HardIronFit field_fit_;               // the sphere the reads lie on (fieldFit())
  std::optional<Stamp> mag_off_since_;  // the field off its reference since
};

}  // namespace attitude_propagator
