// An absolute attitude q_WB as a measurement (docs/design.md §6.9): the residual is the rotation
// vector from the estimate to the fix, r = Log(q^-1 (x) q_fix), H = I, R the fix's covariance
// (body frame, rad^2). As a reset the attitude becomes the fix and P_B its covariance.
#pragma once

#include "attitude_propagator/estimation/measurement.h"

namespace attitude_propagator {

class AttitudeFix final : public Measurement {
 public:
  /// q_WB of unit norm, R_B symmetric and positive semi-definite (the engine checks both).
  AttitudeFix(const Eigen::Quaterniond& q_WB, const Eigen::Matrix3d& R_B, double gate)
      : q_WB_(q_WB), R_B_(R_B), gate_(gate) {}
  MeasurementKind kind() const override { return MeasurementKind::Fix; }
  Linearized linearize(const Eigen::Quaterniond& q_WB) const override;
  double gate() const override { return gate_; }
  void reset(Eigen::Quaterniond& q_WB, ErrorState& e) const override;

 private:
  Eigen::Quaterniond q_WB_;
  Eigen::Matrix3d R_B_;
  double gate_;
};

}  // namespace attitude_propagator
