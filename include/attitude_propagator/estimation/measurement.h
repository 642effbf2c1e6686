// A measurement as the estimation room takes it: a predicted observation of the attitude, its
// residual, its Jacobian with respect to the attitude error, its noise and its gate, and what it
// says outright when it is applied as a reset (an alignment at start, a recovery after a long
// rejection, fix_mode reset). An absolute fix (attitude_fix.h), the gravity direction
// (gravity_direction.h) and the magnetic heading (magnetic_heading.h) are the kinds; a new kind is
// a new class here and a decoder in the message layer (docs/design.md §6.9, numerics.md §7.3).
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "attitude_propagator/estimation/error_state.h"

namespace attitude_propagator {

/// The kinds of measurement, each counted under its own names (EngineCounters).
enum class MeasurementKind { Fix, Gravity, MagneticField };
const char* measurementKindName(MeasurementKind kind);

/// At most three rows: a fix (3), a gravity direction (2), a heading (1).
using MeasurementResidual = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
using MeasurementJacobian = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3>;
using MeasurementNoise = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;

/// A measurement linearised at an estimate q_WB: z - h(q) ~= H dtheta_B + v, v ~ N(0, R). The
/// bias columns of H are zero for every kind here (none observes the bias directly).
struct Linearized {
  MeasurementResidual r;
  MeasurementJacobian H;
  MeasurementNoise R;
};

class Measurement {
 public:
  virtual ~Measurement() = default;
  virtual MeasurementKind kind() const = 0;
  /// The residual, Jacobian and noise at the estimate q_WB (at the measurement's stamp).
  virtual Linearized linearize(const Eigen::Quaterniond& q_WB) const = 0;
  /// The largest r^T S^-1 r accepted (chi-square for the residual's rows).
  virtual double gate() const = 0;
  /// The axes (body frame) a correction may turn: the identity, or a heading's vertical alone.
  virtual Eigen::Matrix3d correctionAxes(const Eigen::Quaterniond& q_WB) const {
    (void)q_WB;
    return Eigen::Matrix3d::Identity();
  }
  /// Applied as a reset: the attitude the measurement says, from the estimate q_WB (what it
  /// does not observe kept), and the error state after it.
  virtual void reset(Eigen::Quaterniond& q_WB, ErrorState& e) const = 0;
};

}  // namespace attitude_propagator
