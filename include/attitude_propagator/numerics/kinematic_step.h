// Kinematic integrators on sampled body rates (docs/design.md §4, docs/numerics.md §2):
// dq_WB/dt = 1/2 q_WB (x) (0, w_B)   (Coutsias–Romero eq. 9).
//
// A step closes the interval between two rate samples when the newer one arrives. It may use
// older samples, never newer ones, so the propagation is causal.
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/integrator.h"

namespace attitude_propagator {

/// What the rate of a sample means.
enum class RateSamples {
  Instantaneous,    ///< w_B at the stamp (a point sample)
  IntervalAverage,  ///< the mean of w_B over (previous stamp, stamp]: delta-angle / dt
};

/// Parses a `rate_samples` value; throws std::invalid_argument naming the accepted values.
RateSamples rateSamplesFromName(const std::string& name);
std::string rateSamplesName(RateSamples kind);

/// A body-rate sample: w_B (rad/s, body frame) at time t (s).
struct RateSample {
  double t = 0.0;
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();
};

/// The newest samples, oldest first, at most kCapacity of them (cf4 needs four).
///
/// A ring of twice the capacity: push() writes past the newest sample and only then lets the
/// oldest go, so undoPush() can restore the window exactly, with no copy on the hot path.
class RateWindow {
 public:
  static constexpr std::size_t kCapacity = 4;

  /// Appends a sample; returns true when the oldest one left the window to make room.
  bool push(const RateSample& sample) {
    samples_[(head_ + size_) & kMask] = sample;
    if (size_ < kCapacity) {
      ++size_;
      return false;
    }
    head_ = (head_ + 1) & kMask;
    return true;
  }
  /// Reverts the last push(), given what it returned.
  void undoPush(bool evicted) {
    if (evicted) {
      head_ = (head_ - 1) & kMask;
    } else {
      --size_;
    }
  }
  void clear() { size_ = 0; }
  std::size_t size() const { return size_; }
  /// i = 0 is the oldest sample held, size() - 1 the newest.
  const RateSample& operator[](std::size_t i) const { return samples_[(head_ + i) & kMask]; }
  const RateSample& newest() const { return (*this)[size_ - 1]; }

  /// The interpolating polynomial through all samples held (degree size() - 1) at time t.
  Eigen::Vector3d interpolate(double t) const;

  /// The same polynomial at two times at once: the Lagrange denominators are shared, which
  /// halves the divisions of cf4's two Gauss-point evaluations.
  void interpolate(double t_a, double t_b, Eigen::Vector3d& w_a, Eigen::Vector3d& w_b) const;

  /// The rate at time t of interval-averaged samples: the derivative of the polynomial
  /// theta(t) through the accumulated delta-angles theta(t_0) = 0,
  /// theta(t_j) = sum_{i=1..j} w_i (t_i - t_{i-1}) (degree size() - 1). The oldest sample's
  /// rate belongs to an interval before the window and is not used. A rate w(t) of degree
  /// size() - 2 is reproduced exactly from its interval means.
  Eigen::Vector3d averagedRate(double t) const;

 private:
  static constexpr std::size_t kMask = 2 * kCapacity - 1;
  std::array<RateSample, 2 * kCapacity> samples_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

/// Noise guard of cf4. The rate at the Gauss points is a weighted sum of the window's rates,
/// A = sum_j a_j w_j and B = sum_j b_j w_j; an error e_j in the samples (or in their stamps,
/// e_j = dw/dt times the stamp error) reaches the step's mean rate (A + B)/2, which sets the
/// rotation angle, with gain sum_j |a_j + b_j| / 2, and the difference A - B, which only enters
/// the commutator term, with gain sum_j |a_j - b_j|. Instantaneous samples: 1.42 and 1.15 for
/// the cubic on a regular grid, 1 and 1.15 for the linear interpolant; interval averages: the
/// mean gain is always 1 and the difference gain 2.31 on a regular grid. A window whose gains
/// exceed these bounds (near-coincident or badly uneven stamps) loses its oldest samples, down
/// to the linear interpolant (the interval's own mean for averaged samples).
constexpr double kMaxNoiseGain = 1.5;
constexpr double kMaxDifferenceGain = 4.0;

/// Advances q_WB across the interval [window[i], window[i + 1]] with a kinematic method and
/// returns the result before renormalisation (so the caller can report |q| - 1): the method's
/// step function from the integrator table. Requires window.size() >= 2 and
/// i + 1 < window.size(). Throws std::invalid_argument for a method that is not kinematic.
Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window, std::size_t i,
                                 RateSamples kind = RateSamples::Instantaneous);

/// Same, across the newest interval (window[size - 2], window[size - 1]).
Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window,
                                 RateSamples kind = RateSamples::Instantaneous);

// The methods' own step functions are the table's (IntegratorInfo::kinematic_step): defined and
// documented in kinematic_step.cpp, declared in integrator.cpp above the rows that name them.

}  // namespace attitude_propagator
