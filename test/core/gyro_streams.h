// What sits between a gyro's rate and the stamped samples a driver delivers: an on-chip
// low-pass filter, a sinc^N decimator, FIFO reads. Shared by the tests
// (test_rate_delay.cpp, test_real_streams.cpp) and the benchmark's real streams
// (bench/kinematic_sweep.cpp). Truths: the filters' group delays at DC are computed from their
// coefficients (tau = sum k b_k / sum b_k - sum k a_k / sum a_k samples).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sampling.h"

namespace gyro_streams {

/// A second-order Butterworth low-pass at fc, by the bilinear transform with the cut-off
/// prewarped: b = K^2 (1, 2, 1) / D, a = (1, 2 (K^2 - 1) / D, (1 - sqrt2 K + K^2) / D),
/// K = tan(pi fc / fs), D = 1 + sqrt2 K + K^2.
struct Butterworth2 {
  std::array<double, 3> b, a;
  explicit Butterworth2(double fc_over_fs) {
    const double K = std::tan(M_PI * fc_over_fs);
    const double D = 1.0 + M_SQRT2 * K + K * K;
    b = {K * K / D, 2.0 * K * K / D, K * K / D};
    a = {1.0, 2.0 * (K * K - 1.0) / D, (1.0 - M_SQRT2 * K + K * K) / D};
  }
  /// Group delay at DC, in samples.
  double dcDelay() const {
    const double sb = b[0] + b[1] + b[2], sa = a[0] + a[1] + a[2];
    return (b[1] + 2.0 * b[2]) / sb - (a[1] + 2.0 * a[2]) / sa;
  }
  /// Filters x (each axis), started in its steady state for x[0].
  std::vector<Eigen::Vector3d> filter(const std::vector<Eigen::Vector3d>& x) const {
    std::vector<Eigen::Vector3d> y(x.size());
    Eigen::Vector3d x1 = x[0], x2 = x[0], y1 = x[0], y2 = x[0];
    for (std::size_t k = 0; k < x.size(); ++k) {
      y[k] = b[0] * x[k] + b[1] * x1 + b[2] * x2 - a[1] * y1 - a[2] * y2;
      x2 = x1;
      x1 = x[k];
      y2 = y1;
      y1 = y[k];
    }
    return y;
  }
};

/// A sinc^N (CIC) decimator by R: N moving averages of R input samples in cascade, every R-th
/// output kept. Its taps are the N-fold convolution of R equal weights (N (R - 1) + 1 taps,
/// symmetric), so its group delay is N (R - 1) / 2 input samples at every frequency.
struct SincDecimator {
  int order, ratio;
  std::vector<double> taps;
  SincDecimator(int n, int r) : order(n), ratio(r), taps{1.0} {
    for (int stage = 0; stage < n; ++stage) {
      std::vector<double> next(taps.size() + r - 1, 0.0);
      for (std::size_t i = 0; i < taps.size(); ++i) {
        for (int j = 0; j < r; ++j) next[i + j] += taps[i] / r;
      }
      taps = next;
    }
  }
  /// Group delay in input samples, from the taps (sum k c_k / sum c_k).
  double delay() const {
    double moment = 0.0, sum = 0.0;
    for (std::size_t k = 0; k < taps.size(); ++k) {
      moment += k * taps[k];
      sum += taps[k];
    }
    return moment / sum;
  }
  /// The output at t of a rate sampled at input_hz (input samples at t, t - 1/input_hz, ...).
  template <class F>
  Eigen::Vector3d output(F rate, double t, double input_hz) const {
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < taps.size(); ++k) y += taps[k] * rate(t - k / input_hz);
    return y;
  }
};

/// FIFO reads: a driver reads the sensor's FIFO every `batch` samples, the read delayed by a
/// latency draw: half-normal, sigma |N(0, 1)| (never negative, so no read is received before its
/// newest sample is taken; a tail as light as the normal's). Repeated: every sample of the
/// read gets the receipt stamp. Spaced: the k-th newest gets the receipt stamp less k periods.
/// A batch of 1 is the per-sample stream with the same latency distribution.
enum class Fifo { Repeated, Spaced };

/// Stamps of samples 0, 1, ... taken at k / hz over `samples_after_anchor` periods: the anchor
/// (k = 0) alone with its exact stamp, then whole reads of `batch` samples (a last partial read
/// is not delivered).
inline std::vector<double> fifoStamps(double hz, int batch, Fifo form, double sigma,
                                      std::uint64_t seed, long samples_after_anchor) {
  std::uint64_t state = seed;
  std::vector<double> stamps{0.0};
  for (long first = 1; first + batch - 1 <= samples_after_anchor; first += batch) {
    const long newest = first + batch - 1;
    const double receipt = newest / hz + sigma * std::abs(normalRandom(state));
    for (long k = first; k <= newest; ++k) {
      stamps.push_back(form == Fifo::Repeated ? receipt : receipt - (newest - k) / hz);
    }
  }
  return stamps;
}

}  // namespace gyro_streams
