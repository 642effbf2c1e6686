// The magnetometer's own field from its reads (docs/numerics.md §7.2, "The magnetometer's own
// field"): a magnetometer turned every way reads the earth's field plus a field of its own (hard
// iron: the board's magnets and currents) that turns with it, so its reads lie on a sphere whose
// centre is that own field, the `mag_bias` to give, and whose radius is the earth's field. The
// sphere |m - c|^2 = r^2 is linear in x = (c, k), k = r^2 - |c|^2: |m|^2 = 2 m.c + k, fitted by
// least squares. The reads go into the normal equations as they come (4 x 4: the same memory at
// any count), in microtesla so that their entries are of one scale.
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Core>

namespace attitude_propagator {

/// T per axis: the centre's standard deviation under which a fit is taken as determined. A
/// centre off by b bends the heading by about |b_h| / |h| rad: 1 uT is 3 degrees where the
/// earth's horizontal field is 20 uT (high latitudes), under a degree at mid latitudes.
constexpr double kHardIronDetermined = 1e-6;

/// How many times its scatter about the sphere the reads must spread along every direction. A
/// read's noise is in the fit's regressors too (errors in variables): along a direction the
/// reads spread s, the centre is pulled toward their mean by the fraction sigma^2 / (s^2 +
/// sigma^2), at most 1 % from 10 times on; and a body turned about one axis (a vehicle) spreads
/// its reads along that axis by their noise alone, however many there are.
constexpr double kHardIronSpread = 10.0;

/// T: the largest read taken, twice the largest own field the engine accepts (kMaxMagBias, 10
/// mT) and more than any earth's field with it; a larger one is a driver's error, and its |m|^4
/// would outweigh every other read in the sums.
constexpr double kMaxFieldRead = 2e-2;

/// The sphere the reads lie on.
struct HardIronSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< T, body frame: the own field
  /// T per axis: the centre's standard deviation from the reads' scatter about the sphere. It
  /// takes the reads as exact where they lie, so along a direction they hardly spread (a body
  /// turned about one axis) it can be small for a centre the noise made up: least_spread tells.
  Eigen::Vector3d centre_stddev = Eigen::Vector3d::Zero();
  double radius = 0.0;   ///< T: the earth's field
  double off_rms = 0.0;  ///< T: how far the reads are from the sphere, root mean square
  /// T: the reads' spread along the direction they spread least (the square root of their
  /// covariance's smallest eigenvalue).
  double least_spread = 0.0;
  std::uint64_t reads = 0;
  /// Every axis of the centre known within kHardIronDetermined, and the reads spread along
  /// every direction at least kHardIronSpread times off_rms.
  bool determined() const;
};

class HardIronFit {
 public:
  /// A field read m_B (T, body frame); a non-finite or all-zero one (no read), or one larger
  /// than kMaxFieldRead, is not taken.
  void add(const Eigen::Vector3d& m_B);
  std::uint64_t count() const { return n_; }
  /// The sphere, or none: fewer than 5 reads (4 unknowns and a scatter), or reads that fix no
  /// sphere (all on one circle: a body turned about a single axis, or not at all).
  std::optional<HardIronSphere> solve() const;

 private:
  Eigen::Matrix4d normal_ = Eigen::Matrix4d::Zero();  // sum a a^T, a = (2 m, 1), m in uT
  Eigen::Vector4d right_ = Eigen::Vector4d::Zero();   // sum a |m|^2
  double squares_ = 0.0;                              // sum |m|^4
  std::uint64_t n_ = 0;
};

}  // namespace attitude_propagator
