// Kinematic integrators on sampled body rates (DESIGN §4, REFERENCE §2):
// dq_WB/dt = 1/2 q_WB (x) (0, w_B)   (seed notes eq. 9).
//
// A step closes the interval between two rate samples when the newer one arrives. It may use
// older samples, never newer ones, so the propagation is causal.
#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Geometry>

#include "attitude_propagator/integrator.h"

namespace attitude_propagator {

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

 private:
  static constexpr std::size_t kMask = 2 * kCapacity - 1;
  std::array<RateSample, 2 * kCapacity> samples_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

/// Advances q_WB across the interval [window[i], window[i + 1]] with a kinematic method and
/// returns the result before renormalisation (so the caller can report |q| - 1).
///
/// - euler: q + (h/2) q (x) (0, w_i)
/// - rk4:   classical RK4 with the rate at the midpoint from the linear interpolant
/// - exp:   q (x) Exp(h w_i)                 (rate of the sample opening the interval held)
/// - exp2:  q (x) Exp(h (w_i + w_{i+1})/2)
/// - cf4:   q (x) Exp(h(a A + b B)) (x) Exp(h(b A + a B)), A, B the window's interpolant at
///          the Gauss points (REFERENCE §2). With four samples that is the cubic; with fewer,
///          the lower-degree interpolant (start-up).
/// Requires window.size() >= 2 and i + 1 < window.size(). Throws std::invalid_argument for a
/// method that is not kinematic.
Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window, std::size_t i);

/// Same, across the newest interval (window[size - 2], window[size - 1]).
Eigen::Quaterniond kinematicStep(Integrator method, const Eigen::Quaterniond& q_WB,
                                 const RateWindow& window);

}  // namespace attitude_propagator
