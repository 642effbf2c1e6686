// The ranges the core accepts from outside, in one place.
//
// Inside them every computation stays in the finite doubles and every call does bounded work;
// outside them an input is refused before it touches the state: a sample or torque returns
// StampOutcome::RejectedOutOfRange, a setter or constructor throws std::invalid_argument, the
// parameter validator throws naming the parameter. Numeric trouble that slips through anyway
// (an integrator that cannot finish an interval) is StampOutcome::FailedStep, never a NaN
// state and never an exception.
//
// How the bounds keep the arithmetic finite: with |w| <= kMaxStateRate and
// kMinInertia <= I <= kMaxInertia, the energy I |w|^2 / 2 <= 5e30 J and |M| = |I w| <= 1e23
// N m s; the squares the closed forms take (G^2, Delta_j ~ I^2 |w|^2 <= 1e46) are far from the
// double range (1.8e308).
#pragma once

#include <cstddef>
#include <cstdint>

namespace attitude_propagator {

// ---- Parameter bounds of the validator (parameters.cpp) --------------------------------------

/// Largest `publish_rate` (Hz). The dynamic model advances on every timer tick; 1 kHz is above
/// any consumer of tf and keeps the timer's own work under a few percent of a core.
constexpr double kMaxPublishRate = 1000.0;

/// Smallest `max_step` (s) other than 0. With kMaxGridStepsPerCall it bounds the work of one
/// call; below it the grid only burns CPU (a 100 kHz grid is already finer than any input).
constexpr double kMinMaxStep = 1e-5;

/// Largest `max_dt` (s), and largest `max_step`. A longer silence is an outage: the state is
/// held, not integrated across minutes of extrapolated input.
constexpr double kMaxMaxDt = 60.0;

/// Largest max_dt / max_step: the fixed-step grid points one call may have to cross (about
/// 10 ms of rk4 at 100 ns a step).
constexpr double kMaxGridStepsPerCall = 1e5;

/// `tolerance` of dopri5 in [kMinTolerance, kMaxTolerance]. Below 1e-12 the error estimate is
/// round-off (ten ulps of a unit quaternion per sub-step), so step-size control cannot succeed
/// and only shrinks the step; above 1e-2 the result is not worth integrating.
constexpr double kMinTolerance = 1e-12;
constexpr double kMaxTolerance = 1e-2;

/// Largest `torque_timeout` (s): an hour. Keeps stamp + timeout an ordinary, exact sum.
constexpr double kMaxTorqueTimeout = 3600.0;
/// Largest `max_future` (s): how far ahead of the clock an input may be stamped. An hour covers
/// any clock a system would still call synchronised.
constexpr double kMaxFuture = 3600.0;

/// Largest `angular_velocity_stddev` (rad/s), and the root of the largest per-axis variance a
/// rate covariance may carry (checkRateCovariance). A MEMS gyro's noise is about 1e-2 rad/s
/// per sample; 1e3 rad/s is noise no sensor reports, only a unit mistake or an attack.
constexpr double kMaxRateStddev = 1e3;
constexpr double kMaxRateVariance = kMaxRateStddev * kMaxRateStddev;
/// Largest `gyro_bias_stddev` (rad/s), and the ceiling of the bias estimate's standard deviation
/// per axis (a random walk grows it no further). A step of h adds about h^2 sigma_b^2 to the
/// attitude's variance: at 10 rad/s a step up to 0.3 s stays below its ceiling pi^2, where the
/// covariance would be capped (and its correlations with the bias scaled down with it).
/// A MEMS gyro's bias is below 0.1 rad/s.
constexpr double kMaxGyroBiasStddev = 10.0;

// ---- Door bounds of the propagators ----------------------------------------------------------

/// Largest body rate |w| (rad/s) a rate sample, a set state or an initial state may carry.
/// 1e5 rad/s (about 1e6 rpm) is above any machine (turbine and dental-drill rotors reach
/// 1e4 rad/s; gyros measure up to about 70 rad/s).
constexpr double kMaxBodyRate = 1e5;

/// Principal moments of inertia (kg m^2) a body may have: from a gram-sized part at a
/// millimetre (1e-10) with margin, up to far beyond a space station (1e8).
constexpr double kMinInertia = 1e-15;
constexpr double kMaxInertia = 1e15;

/// Largest |w| (rad/s) a propagated state may reach. Above kMaxBodyRate because a free body
/// that starts below the door may legitimately speed up about an axis of small moment (by up to
/// sqrt(I_max / I_min)) and a torque may spin it up; a step whose result leaves this bound is a
/// failed step (the state is held), which keeps every later product finite.
constexpr double kMaxStateRate = 1e3 * kMaxBodyRate;

/// Largest |torque| (N m) a torque sample may carry: the torque that spins the heaviest body
/// from rest to kMaxStateRate within the shortest grid step, I_max w_max / kMinMaxStep = 1e28.
/// A larger torque can only produce failed steps.
constexpr double kMaxTorque = kMaxInertia * kMaxStateRate / kMinMaxStep;

/// Default DynamicConfig::step_budget: the integrator work one call of a DynamicPropagator may
/// spend (one unit per fixed step or exact evaluation, per trial sub-step of dopri5). 2^17
/// units are about 0.03 s of rk4 or dopri5 and 0.15 s of the worst implicit midpoint step
/// (100 iterations), so a node stays responsive (services, SIGINT) whatever it is fed; a call
/// that needs more returns FailedStep. It covers kMaxGridStepsPerCall fixed steps (the finest
/// grid the validator accepts across max_dt) with 30 % to spare.
constexpr std::uint64_t kDefaultStepBudget = std::uint64_t{1} << 17;

// ---- Covariance ------------------------------------------------------------------------------

/// Ceiling of the orientation variance (rad^2) per axis: pi^2, an error of one half-turn, i.e.
/// no knowledge of the orientation at all. propagateOrientationCovariance saturates there
/// instead of growing without bound (and overflowing).
constexpr double kMaxOrientationVariance = 3.14159265358979323846 * 3.14159265358979323846;

// ---- Late absolute fixes (docs/design.md §6.9) ---------------------------------------------

/// Largest `fix_history` (s): how far back a fix may be stamped and still be applied at its stamp.
constexpr double kMaxFixHistory = 10.0;
/// The history's memory bound: at most this many steps of the model are kept (the oldest dropped
/// first, so at high rates the history is shorter than fix_history). One entry is the step
/// (an input as applied, or a dynamic grid advance), the model's state after it and the error
/// state, sizeof(FixHistoryEntry) bytes (1792 on x86-64, printed by test_fixes.cpp): 7.3 MB at
/// most, 10 s at 400 Hz; in the dynamic model each entry also holds the propagator's state on
/// the heap (1168 bytes more, test_dynamic_fixes.cpp): 12.1 MB at most. Nothing is kept until
/// the first fix is submitted.
constexpr std::size_t kMaxFixHistorySamples = 4096;
/// Gyro bias samples stamped ahead of the rates wait for them, at most this many; past it the one
/// stamped furthest ahead is dropped (bias_queue_full). A bias stream should be slow (a
/// calibration): this many ahead means its stamps are wrong.
constexpr std::size_t kMaxPendingBias = 64;
/// Fixes stamped ahead of the newest rate wait for the rates to reach them, at most this many;
/// past it the one stamped furthest ahead is dropped (fixes_queue_full).
constexpr std::size_t kMaxPendingFixes = 8;
/// A fix stamped before fixes already applied is applied at its stamp and those after it are
/// applied again, in stamp order (each a replay). The newest this many applied fixes are kept
/// for it; a fix stamped before one no longer kept is too old (fixes_too_old).
constexpr std::size_t kMaxFixesReapplied = 8;
/// A fix's quaternion must have |q| within this of 1 (it is then normalised).
constexpr double kFixUnitTolerance = 1e-5;
/// Fuse mode: after this many fixes in a row rejected by the gate, the next one that fails the
/// gate is applied as a reset: by then the estimate, not the fixes, is what is wrong.
constexpr int kFixRejectionRun = 5;
/// Floor (rad^2) on the innovation covariance's diagonal, so an exact fix of an exact estimate
/// (P = R = 0 on an axis) still has an invertible S: 1 nrad.
constexpr double kMinInnovationVariance = 1e-18;

// ---- Gravity and the magnetic field as measurements (docs/design.md §6.10) -------------------

/// The gravity direction's gate: chi-square with 2 degrees of freedom at 99.9 %.
constexpr double kAccelGate = 13.816;
/// The heading's gate: chi-square with 1 degree of freedom at 99.9 %.
constexpr double kMagGate = 10.828;
/// An accelerometer sample whose |f| is off g by more than this fraction is linear
/// acceleration (a bump, a launch, free fall) and not used (accel_rejected_magnitude).
constexpr double kAccelMagnitudeTolerance = 0.1;
/// A magnetometer sample whose |m| is off the learned magnitude by more than this fraction, or
/// whose dip is off the learned dip by more than kMagDipTolerance (rad), is a disturbance and
/// not used (mag_rejected_magnitude).
constexpr double kMagMagnitudeTolerance = 0.15;
constexpr double kMagDipTolerance = 0.1745329251994330;  // 10 degrees
/// Largest |mag_bias| (T): 10 mT, the bound of mag_stddev too; a magnetometer's own field
/// (hard iron: a board's magnets and currents) is below a millitesla, the earth's 25-65 uT.
constexpr double kMaxMagBias = 1e-2;
/// How fast the learned field follows the accepted samples (fraction per sample).
constexpr double kMagReferenceFollow = 0.01;
/// Seconds of gate rejections in a row after which the next gravity sample the gate rejects is
/// applied as a reset (counted accel_recovered): by then the estimate, not the sensor, is what
/// is wrong.
constexpr double kAccelRecovery = 10.0;
/// The same for the field (mag_recovered), and the time a field off its learned magnitude or
/// dip takes to become the reference: longer, since a disturbance near a building, a vehicle
/// or a motor lasts, and the gyro holds the heading meanwhile (its vertical bias estimated).
constexpr double kMagRecovery = 30.0;
/// Seconds over which the linear acceleration seen in the gravity samples is averaged (an
/// exponential window): a turn or a braking lasts seconds, and while it lasts the gravity
/// direction is trusted less. Chosen from that, not fitted to a stream.
constexpr double kLinearAccelerationWindow = 1.0;
/// Seconds over which the disagreement between the gravity direction measured and the
/// estimate's vertical is averaged for the published tilt covariance (TiltDisagreement): longer
/// than a hand's or a swell's back and forth (periods of 4-12 s), so what averages out there
/// does not count, and a turn or a braking, which lasts, does. Chosen from that, not fitted.
constexpr double kTiltDisagreementWindow = 10.0;
/// Gravity and field samples stamped ahead of the newest rate wait for the rates to reach them,
/// at most this many; past it the one stamped furthest ahead is dropped (*_queue_full).
constexpr std::size_t kMaxPendingMeasurements = 64;
/// rad/s: the rate noise per sample assumed with use_accel or use_mag when neither rate_stddev
/// nor the message gives one, so the covariance grows between measurements (a MEMS gyro's
/// noise at 100 Hz, 0.3 deg/s per sample).
constexpr double kAidedRateStddev = 0.005;

}  // namespace attitude_propagator
