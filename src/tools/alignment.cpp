#include "alignment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/SVD>

#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {
namespace tools {

namespace {

// |w| counts as varying when its variance exceeds this share of its mean square (1 % in
// magnitude); below, only the directions can tell the offset.
constexpr double kVaryingMagnitude = 1e-4;
// A criterion whose range over the searched offsets is below this share of the mean square
// rate cannot tell one offset from another (e.g. coning with an unknown mount, where a time
// shift is exactly a rotation of the mount).
constexpr double kFlatCriterion = 1e-6;
// Offsets at which fewer than this share of the gyro samples meet the truth are not tried.
constexpr double kMinOverlap = 0.5;
// Relative weight of the identity added to Wahba's matrix: picks the rotation closest to the
// identity among equally good ones, moving a well-determined one by about this much.
constexpr double kIdentityPrior = 1e-9;

struct Pairs {
  std::vector<Eigen::Vector3d> gyro;   // w_S(t_i)
  std::vector<Eigen::Vector3d> truth;  // w_T(t_i + offset)
};

Pairs pairsAt(const std::vector<TimedRate>& gyro, const RateTrack& truth, double offset) {
  Pairs p;
  p.gyro.reserve(gyro.size());
  p.truth.reserve(gyro.size());
  for (const TimedRate& g : gyro) {
    if (const auto w_T = truth.at(g.t + offset)) {
      p.gyro.push_back(g.w);
      p.truth.push_back(*w_T);
    }
  }
  return p;
}

double magnitudeCost(const Pairs& p) {
  double sum = 0.0;
  for (std::size_t i = 0; i < p.gyro.size(); ++i) {
    const double d = p.gyro[i].norm() - p.truth[i].norm();
    sum += d * d;
  }
  return sum / double(p.gyro.size());
}

double vectorCost(const Pairs& p, const std::optional<Eigen::Matrix3d>& mount) {
  const Eigen::Matrix3d R = mount ? *mount : wahba(p.gyro, p.truth);
  double sum = 0.0;
  for (std::size_t i = 0; i < p.gyro.size(); ++i) sum += (p.gyro[i] - R * p.truth[i]).squaredNorm();
  return sum / double(p.gyro.size());
}

double meanSquare(const std::vector<TimedRate>& gyro) {
  double sum = 0.0;
  for (const auto& g : gyro) sum += g.w.squaredNorm();
  return gyro.empty() ? 0.0 : sum / double(gyro.size());
}

double magnitudeVariance(const std::vector<TimedRate>& gyro) {
  double sum = 0.0, sum2 = 0.0;
  for (const auto& g : gyro) {
    sum += g.w.norm();
    sum2 += g.w.squaredNorm();
  }
  const double n = double(gyro.size());
  return n > 0 ? std::max(0.0, sum2 / n - (sum / n) * (sum / n)) : 0.0;
}

}  // namespace

double medianInterval(const std::vector<double>& times) {
  if (times.size() < 2) return 0.0;
  std::vector<double> d;
  d.reserve(times.size() - 1);
  for (std::size_t i = 1; i < times.size(); ++i) d.push_back(times[i] - times[i - 1]);
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

Eigen::Quaterniond slerp(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double s) {
  return a * expMap(s * logMap(a.conjugate() * b));
}

Eigen::Quaterniond interpolateAttitude(const TimedAttitude* nodes, std::size_t n, double t) {
  std::size_t b = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (std::abs(nodes[i].t - t) < std::abs(nodes[b].t - t)) b = i;
  }
  if (n == 1 || nodes[b].t == t) return nodes[b].q;
  const Eigen::Quaterniond base_c = nodes[b].q.conjugate();
  Eigen::Vector3d phi = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (i == b) continue;  // its rotation vector is zero
    double l = 1.0;        // the Lagrange basis polynomial of node i at t
    for (std::size_t j = 0; j < n; ++j) {
      if (j != i) l *= (t - nodes[j].t) / (nodes[i].t - nodes[j].t);
    }
    phi += l * logMap(base_c * nodes[i].q);
  }
  return (nodes[b].q * expMap(phi)).normalized();
}

namespace {

/// d/dx of the Lagrange basis polynomial of node i at x, for nodes x[0..n).
double lagrangeDerivative(const double* x, std::size_t n, std::size_t i, double at) {
  double sum = 0.0;
  for (std::size_t m = 0; m < n; ++m) {
    if (m == i) continue;
    double term = 1.0 / (x[i] - x[m]);
    for (std::size_t j = 0; j < n; ++j) {
      if (j != i && j != m) term *= (at - x[j]) / (x[i] - x[j]);
    }
    sum += term;
  }
  return sum;
}

}  // namespace

std::vector<TimedRate> differentiate(const std::vector<TimedAttitude>& attitudes, double gap) {
  const std::size_t n = attitudes.size();
  // close[k]: attitudes k and k + 1 are close enough to differentiate between.
  std::vector<bool> close(n > 0 ? n - 1 : 0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double h = attitudes[k + 1].t - attitudes[k].t;
    close[k] = h > 0.0 && h <= gap;
  }
  auto full = [&](std::size_t k) {  // a five-point stencil about k
    return k >= 2 && k + 2 < n && close[k - 2] && close[k - 1] && close[k] && close[k + 1];
  };
  std::vector<TimedRate> rates;
  for (std::size_t k = 0; k < n; ++k) {
    if (full(k)) {
      // phi(t) = Log(q_k^c q(t)) has phi'(t_k) = w(t_k) exactly (the right Jacobian is the
      // identity at 0): its derivative through five points is the rate at t_k to O(h^4).
      const Eigen::Quaterniond base_c = attitudes[k].q.conjugate();
      double x[5];
      for (std::size_t i = 0; i < 5; ++i) x[i] = attitudes[k + i - 2].t - attitudes[k].t;
      Eigen::Vector3d w = Eigen::Vector3d::Zero();
      for (std::size_t i = 0; i < 5; ++i) {
        if (i != 2) w += lagrangeDerivative(x, 5, i, 0.0) * logMap(base_c * attitudes[k + i - 2].q);
      }
      rates.push_back({attitudes[k].t, w});
    }
    // Where a stencil is missing on either side: the interval's mean rate at its mid-time.
    if (k + 1 < n && close[k] && (!full(k) || !full(k + 1))) {
      const double h = attitudes[k + 1].t - attitudes[k].t;
      rates.push_back(
          {attitudes[k].t + 0.5 * h, logMap(attitudes[k].q.conjugate() * attitudes[k + 1].q) / h});
    }
  }
  return rates;
}

std::optional<Eigen::Vector3d> RateTrack::at(double t) const {
  const std::size_t n = rates_.size();
  if (n < 2 || t < rates_.front().t || t > rates_.back().t) return std::nullopt;
  if (cursor_ >= n || rates_[cursor_].t > t) {
    const auto it = std::upper_bound(rates_.begin(), rates_.end(), t,
                                     [](double x, const TimedRate& r) { return x < r.t; });
    cursor_ = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - rates_.begin() - 1, 0));
  }
  while (cursor_ + 1 < n && rates_[cursor_ + 1].t <= t) ++cursor_;
  if (cursor_ + 1 >= n) return rates_.back().w;  // t is the last time exactly
  const std::size_t c = cursor_;
  auto near = [&](std::size_t i) { return rates_[i + 1].t - rates_[i].t <= gap_; };
  if (!near(c)) return std::nullopt;
  if (c >= 1 && c + 2 < n && near(c - 1) && near(c + 1)) {
    // A cubic through the four rates about t: O(h^4), where a line would be off by up to
    // h^2 |w''| / 8 (enough, with the mount fitted at each offset, to bias the offset).
    double x[4];
    for (std::size_t i = 0; i < 4; ++i) x[i] = rates_[c - 1 + i].t;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < 4; ++i) {
      double l = 1.0;
      for (std::size_t j = 0; j < 4; ++j) {
        if (j != i) l *= (t - x[j]) / (x[i] - x[j]);
      }
      w += l * rates_[c - 1 + i].w;
    }
    return w;
  }
  const TimedRate& a = rates_[c];
  const TimedRate& b = rates_[c + 1];
  const double s = (t - a.t) / (b.t - a.t);
  return (1.0 - s) * a.w + s * b.w;
}

Eigen::Matrix3d wahba(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                      double* second_singular_ratio) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) H += a[i] * b[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> plain(H);
  const double s1 = plain.singularValues()(0);
  if (second_singular_ratio)
    *second_singular_ratio = s1 > 0.0 ? plain.singularValues()(1) / s1 : 0.0;
  H += kIdentityPrior * std::max(s1, std::numeric_limits<double>::min()) *
       Eigen::Matrix3d::Identity();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // R = U diag(1, 1, det(U V^T)) V^T: the nearest proper rotation (no reflection).
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

OffsetEstimate estimateOffset(const std::vector<TimedRate>& gyro, const RateTrack& truth,
                              double max_offset, double step,
                              const std::optional<Eigen::Matrix3d>& mount,
                              const std::function<void()>& checkpoint) {
  OffsetEstimate e;
  if (gyro.empty()) {
    e.how = "not observable: no rates";
    return e;
  }
  const double scale = meanSquare(gyro);
  const bool by_magnitude = magnitudeVariance(gyro) > kVaryingMagnitude * scale;
  auto cost = [&](double offset, bool magnitude) {
    if (checkpoint) checkpoint();
    const Pairs p = pairsAt(gyro, truth, offset);
    if (double(p.gyro.size()) < kMinOverlap * double(gyro.size())) {
      return std::numeric_limits<double>::infinity();
    }
    return magnitude ? magnitudeCost(p) : vectorCost(p, mount);
  };
  // An offset counts only when at least half of the gyro samples meet the truth, t + offset in
  // [truth begin, truth end]; outside [truth begin - t_m, truth end - t_m], with t_m the
  // gyro's median time, at least half of them miss it. The range is cut to that, however
  // large max_offset is.
  std::vector<double> times(gyro.size());
  for (std::size_t i = 0; i < gyro.size(); ++i) times[i] = gyro[i].t;
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  const double median = times[times.size() / 2];
  const double lo = std::max(-max_offset, truth.begin() - median);
  const double hi = std::min(max_offset, truth.end() - median);
  // Coarse: every step over the range, the step widened so that the pairings stay bounded.
  const double points = std::max(64.0, std::floor(kMaxOffsetPairings / double(gyro.size())));
  const double coarse = std::max(step, (hi - lo) / (points - 1.0));
  double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
  double worst_cost = 0.0;
  if (lo <= hi) {
    // |lo|, |hi| <= max_offset and coarse >= (hi - lo) / (points - 1): the indices stay small.
    const auto j_lo = static_cast<long long>(std::ceil(lo / coarse));
    const auto j_hi = static_cast<long long>(std::floor(hi / coarse));
    for (long long j = j_lo; j <= j_hi; ++j) {
      const double c = cost(double(j) * coarse, by_magnitude);
      if (!std::isfinite(c)) continue;
      worst_cost = std::max(worst_cost, c);
      if (c < best_cost) best_cost = c, best = double(j) * coarse;
    }
  }
  char searched[128];
  if (lo <= hi) {
    std::snprintf(searched, sizeof searched, "; searched %+.4g..%+.4g s in steps of %.3g ms%s", lo,
                  hi, coarse * 1e3, coarse > step ? " (widened to bound the search)" : "");
  } else {
    std::snprintf(searched, sizeof searched, "; no offset within +-%.4g s meets the truth",
                  max_offset);
  }
  if (!std::isfinite(best_cost) || worst_cost - best_cost <= kFlatCriterion * scale) {
    e.how = std::string(!std::isfinite(best_cost) ? "not observable: rates and truth do not overlap"
                        : mount                   ? "not observable: the rates do not change enough"
                                : "not observable with an unknown mount (a time shift of this "
                                  "motion is a rotation; give --mount or --offset)") +
            searched;
    return e;
  }
  // Fine: golden-section search on the vectors within one step of the coarse minimum.
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = best - coarse, b = best + coarse;
  double x1 = b - phi * (b - a), x2 = a + phi * (b - a);
  double c1 = cost(x1, false), c2 = cost(x2, false);
  for (int it = 0; it < 60 && b - a > 1e-9; ++it) {
    if (c1 < c2) {
      b = x2, x2 = x1, c2 = c1;
      x1 = b - phi * (b - a), c1 = cost(x1, false);
    } else {
      a = x1, x1 = x2, c1 = c2;
      x2 = a + phi * (b - a), c2 = cost(x2, false);
    }
  }
  e.offset = 0.5 * (a + b);
  e.observable = true;
  e.how = std::string(by_magnitude ? "|w| matched" : "rate vectors matched") + ", refined on " +
          (mount ? "the vectors through the given mount" : "the vectors through the best mount") +
          searched;
  return e;
}

Eigen::Matrix3d estimateMount(const std::vector<TimedRate>& gyro, const RateTrack& truth,
                              double offset, double* second_singular_ratio) {
  const Pairs p = pairsAt(gyro, truth, offset);
  return wahba(p.gyro, p.truth, second_singular_ratio);
}

std::vector<double> rankingWindows(double truth_period, double rate_period) {
  const double shortest = kRankingWindowSamples * std::max(truth_period, rate_period);
  std::vector<double> windows{shortest};
  while (windows.back() * 2.0 <= kLongestRankingWindow) windows.push_back(windows.back() * 2.0);
  return windows;
}

std::size_t chooseRankingWindow(const std::vector<std::vector<double>>& rpe, double floor) {
  std::optional<std::size_t> measured;
  for (std::size_t w = 0; w < rpe.size(); ++w) {
    double lo = std::numeric_limits<double>::infinity();
    for (const double e : rpe[w]) {
      if (!std::isnan(e)) lo = std::min(lo, e);
    }
    if (!std::isfinite(lo)) continue;
    if (lo > floor) return w;
    measured = w;
  }
  return measured.value_or(0);
}

std::optional<std::string> turnMismatch(double truth_turn, double rates_turn) {
  if (!(std::max(truth_turn, rates_turn) >= kMinJudgedTurn)) return std::nullopt;
  if (truth_turn <= kTurnRatioLimit * rates_turn && rates_turn <= kTurnRatioLimit * truth_turn) {
    return std::nullopt;
  }
  char text[256];
  std::snprintf(text, sizeof text,
                "the truth turns through %.3g rad where the rates turn through %.3g rad (%.2g "
                "times as far; no setting explains more than %.3g times either way)",
                truth_turn, rates_turn, rates_turn > 0.0 ? truth_turn / rates_turn : INFINITY,
                kTurnRatioLimit);
  return std::string(text);
}

}  // namespace tools
}  // namespace attitude_propagator
