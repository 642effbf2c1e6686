// The magnetometer as a measurement of the heading alone (docs/numerics.md §7.3). The measured
// field is turned into the world with the estimate, m_W = C_WB m_B, and its horizontal part h
// compared with magnetic north: in ENU the field points to (sin D, cos D) east and north, D the
// declination (east of true north positive), so the reference heading is pi/2 - D from east. The
// residual is the signed angle r = wrap(pi/2 - D - atan2(h_y, h_x)) about the world's up; a body
// error dtheta_B turns the measured field by C_WB (dtheta_B x m_B), so H = -n^T C_WB [m_B]x / |h|
// (1 row, n across h): u^T about the body's up u, plus tan(dip) times a tilt about h's
// direction, so the innovation's covariance holds the tilt's uncertainty too. The gain's
// attitude rows are kept to u: the field never moves roll and pitch, whatever its dip or a
// tilted disturbance. The noise is the field's covariance across h over |h|^2.
#pragma once

#include <optional>

#include "attitude_propagator/estimation/measurement.h"

namespace attitude_propagator {

class MagneticHeading final : public Measurement {
 public:
  /// m_B: the field (tesla, body frame); covariance_B its noise (T^2); declination (rad);
  /// gate: chi-square with 1 degree of freedom; tilt_variance: rad^2 per axis the tilt may be
  /// off beyond what the covariance says (gravity's linear acceleration seen lately, over g^2),
  /// passed into the heading through the dip.
  MagneticHeading(const Eigen::Vector3d& m_B, const Eigen::Matrix3d& covariance_B,
                  double declination, double gate, double tilt_variance = 0.0);
  MeasurementKind kind() const override { return MeasurementKind::MagneticField; }
  Linearized linearize(const Eigen::Quaterniond& q_WB) const override;
  double gate() const override { return gate_; }
  Eigen::Matrix3d correctionAxes(const Eigen::Quaterniond& q_WB) const override;
  /// The heading turned to the field's (tilt kept); its variance becomes the measurement's, its
  /// correlations dropped.
  void reset(Eigen::Quaterniond& q_WB, ErrorState& e) const override;

 private:
  Eigen::Vector3d m_B_;
  Eigen::Matrix3d covariance_B_;
  double reference_heading_;  // pi/2 - declination, from east about up
  double gate_;
  double tilt_variance_;
};

/// The field's own signature, learned from the samples: its magnitude and its dip (rad, positive
/// downward: asin(-m_W,z / |m|) in ENU). A sample whose magnitude is off by more than
/// kMagMagnitudeTolerance (relative) or whose dip is off by more than kMagDipTolerance is a
/// disturbance (a motor, a steel beam) and not used. The reference starts from the first sample
/// judged, follows the accepted ones slowly (kMagReferenceFollow per sample), and starts again
/// from a sample that recovers after a long rejection.
class MagneticReference {
 public:
  /// Whether m_B, seen through q_WB, matches the reference (true before one is known).
  bool matches(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB) const;
  /// An accepted sample: the reference follows it (or starts from it).
  void follow(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB);
  /// A recovery: the reference starts again from this sample.
  void restart(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB);
  void forget() { magnitude_.reset(); }
  std::optional<double> magnitude() const { return magnitude_; }
  double dip() const { return dip_; }

 private:
  std::optional<double> magnitude_;
  double dip_ = 0.0;
};

/// The dip (rad, positive downward) of m_B seen through q_WB.
double dipAngle(const Eigen::Vector3d& m_B, const Eigen::Quaterniond& q_WB);

}  // namespace attitude_propagator
