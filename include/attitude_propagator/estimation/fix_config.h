// What an absolute attitude fix does at its stamp, and the gyro bias estimate's configuration
// (docs/design.md §6.9, numerics.md §7.1).
#pragma once

namespace attitude_propagator {

/// What an absolute fix does at its stamp (docs/design.md §6.9).
enum class FixMode {
  Reset,  ///< the attitude at the fix's stamp is replaced, P_B becomes the fix's covariance
  Fuse,   ///< a multiplicative EKF update at the fix's stamp, behind a chi-square gate
};
const char* fixModeName(FixMode mode);

/// Absolute attitude fixes and the gyro bias estimate (docs/design.md §6.9, numerics.md §7.1).
struct FixConfig {
  FixMode mode = FixMode::Fuse;
  /// Seconds of rate inputs kept to apply a late fix at its stamp, in (0, kMaxFixHistory];
  /// kept only from the first fix on.
  double history = 1.0;
  /// Fuse: largest squared Mahalanobis distance r^T S^-1 r of an innovation accepted; the
  /// default is the 99.9 % point of chi-square with 3 degrees of freedom.
  double gate = 16.266;
  /// rad per axis, for a fix that carries no covariance (all zero).
  double stddev = 0.01;
  /// The gyro bias joins the error state (6x6: attitude error, bias error).
  bool estimate_gyro_bias = false;
  /// rad/s/sqrt(s): the bias' random walk (a MEMS gyro's, docs/parameters.md)
  double gyro_bias_random_walk = 1e-5;
  /// rad/s: prior standard deviation per axis (0.57 deg/s: a MEMS gyro's, docs/parameters.md)
  double gyro_bias_stddev = 0.01;
};

}  // namespace attitude_propagator
