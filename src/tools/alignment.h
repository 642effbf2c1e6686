// Aligning a rate stream with a truth attitude stream (evaluate_bag): the time offset between
// the two clocks, the rotation between the rate sensor and the truth's body, interpolation of
// the truth between its samples. No ROS: plain Eigen on stamps in seconds.
//
// Frames: the truth gives q_VT (truth body T in the truth's fixed frame V); a rate sensor S
// measures w_S; integrating it gives q_WS. With q_ST the mount (x_S = q_ST x_T, so
// w_S = q_ST w_T) and A = q_VW a fixed rotation, q_VT(t + offset) = A q_WS(t) q_ST.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace attitude_propagator {
namespace tools {

struct TimedRate {
  double t;  ///< s
  Eigen::Vector3d w;
};

struct TimedAttitude {
  double t;  ///< s
  Eigen::Quaterniond q;
};

/// Median of the intervals between consecutive times (0 with fewer than two).
double medianInterval(const std::vector<double>& times);

/// q_a Exp(s Log(q_a^c q_b)): the rotation a fraction s of the way from q_a to q_b along the
/// shorter arc (slerp, through the accurate log and exp maps).
Eigen::Quaterniond slerp(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double s);

/// The attitude at t from n attitudes (1 to kInterpolationNodes) at distinct times around
/// it: the polynomial of degree n - 1 through their rotation vectors Log(q_b^c q_i) relative
/// to the node nearest t (Lagrange), mapped back, q_b Exp(phi(t)). With six nodes at spacing h
/// about t its error is about 0.005 h^6 |phi^(6)|: 1e-12 rad for the coning scene at 200 Hz,
/// far below any integrator's error there (cf4: 1e-8 to 1e-7). Times in seconds, best
/// relative to t (the arithmetic then keeps full precision).
constexpr std::size_t kInterpolationNodes = 6;
Eigen::Quaterniond interpolateAttitude(const TimedAttitude* nodes, std::size_t n, double t);

/// Body rates from attitudes: at each attitude with two neighbours on either side, none further
/// than `gap` from the next, the derivative at t_k of the degree-4 polynomial through
/// Log(q_k^c q_i) (the rate at t_k to O(h^4)); elsewhere, between two attitudes closer than
/// `gap`, w = Log(q_k^c q_(k+1)) / (t_(k+1) - t_k) at the mid-time (O(h^2)). In time order.
std::vector<TimedRate> differentiate(const std::vector<TimedAttitude>& attitudes, double gap);

/// Interpolation of rates between neighbours closer than `gap`: a cubic through the four about
/// t where they are all that close, else a line.
class RateTrack {
 public:
  RateTrack(const std::vector<TimedRate>& rates, double gap) : rates_(rates), gap_(gap) {}
  /// The rate at t, or nothing outside the track or inside a gap. Calls with increasing t
  /// are cheapest (a cursor moves forward; a smaller t searches from the start).
  std::optional<Eigen::Vector3d> at(double t) const;
  /// The first and last times of the track (0 for an empty one).
  double begin() const { return rates_.empty() ? 0.0 : rates_.front().t; }
  double end() const { return rates_.empty() ? 0.0 : rates_.back().t; }

 private:
  const std::vector<TimedRate>& rates_;
  double gap_;
  mutable std::size_t cursor_ = 0;
};

/// The rotation R (a proper rotation) minimising sum |a_i - R b_i|^2 (Wahba's problem, by
/// the SVD of sum a_i b_i^T). A tiny multiple of the identity is added to that sum, so when
/// the vectors leave a rotation unobservable (all along one axis) the solution closest to the
/// identity is chosen. `second_singular_ratio` receives sigma_2 / sigma_1 of the sum (near 0:
/// one axis only).
Eigen::Matrix3d wahba(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                      double* second_singular_ratio = nullptr);

struct OffsetEstimate {
  double offset = 0.0;      ///< s: truth time = rate time + offset
  bool observable = false;  ///< false: the data cannot tell (offset 0 used)
  std::string how;          ///< which criterion decided, for the report
};

/// The offset that best matches the gyro rates w_S(t_i) with the truth's rates w_T(t_i +
/// offset), searched in [-max_offset, max_offset] on a grid of `step`, then refined by
/// golden-section search within one step. Criterion: the mean squared difference of |w|
/// (which no mount changes) when |w| varies; otherwise (a constant |w|, e.g. coning) of the
/// vectors, through `mount` R_ST or, without one, the best rotation per offset.
///
/// Bounded: only offsets at which half of the gyro samples can meet the truth are tried (the
/// range is cut to the data's span), and the grid has at most kMaxOffsetPairings / gyro.size()
/// points, its step widened when needed (`how` says so), so one search pairs at most about
/// kMaxOffsetPairings samples whatever max_offset is. `checkpoint` is called before each trial
/// offset and may throw to stop the search (Ctrl-C).
OffsetEstimate estimateOffset(const std::vector<TimedRate>& gyro, const RateTrack& truth,
                              double max_offset, double step,
                              const std::optional<Eigen::Matrix3d>& mount,
                              const std::function<void()>& checkpoint = {});

/// About a second of pairing and comparing samples on one core (20 ns a pairing).
constexpr double kMaxOffsetPairings = 5e7;

/// The mount R_ST fitted by wahba() to w_S(t_i) and w_T(t_i + offset).
Eigen::Matrix3d estimateMount(const std::vector<TimedRate>& gyro, const RateTrack& truth,
                              double offset, double* second_singular_ratio);

// ---------------------------------------------------------------------------------------------
// The evaluation's decision rules (evaluate_bag_core applies them; docs/bag_tools.md)
// ---------------------------------------------------------------------------------------------

/// The longest window over which the relative error is measured for the ranking, s.
constexpr double kLongestRankingWindow = 10.0;
/// Samples of the slower stream a ranking window spans at least: fewer, and the error over it
/// is the truth's noise at its two ends rather than the integration between them.
constexpr double kRankingWindowSamples = 10.0;

/// The windows the relative error is measured over for the ranking: from kRankingWindowSamples
/// periods of the slower stream, doubling, up to kLongestRankingWindow (the first alone when
/// it is longer).
std::vector<double> rankingWindows(double truth_period, double rate_period);

/// The window the methods are ranked over: the shortest at which the smallest of their
/// relative errors is above `floor` (what the truth resolves: at shorter windows its white
/// noise at the two ends hides the methods' differences), or the longest measured when none
/// is. The drift of the gyro's bias and of the truth itself grows with the window, so the
/// shortest resolved window is where it hides the integrator's own error least. rpe[w][m]:
/// the RMS relative error of method m over window w, windows from the shortest (NaN: not
/// measured). Returns the index of the window (0 when none is measured).
std::size_t chooseRankingWindow(const std::vector<std::vector<double>>& rpe, double floor);

/// A truth turns through about the angle the rates integrate to: a gyro's scale error is a few
/// percent and no setting changes it, so a ratio of the two turned angles beyond this factor
/// (either way) is no truth of these rates (e.g. a wheeled robot's odometry yaw).
constexpr double kTurnRatioLimit = 2.0;
/// Turns smaller than this (rad, the larger of the two) are not judged: a still recording's
/// angles are noise.
constexpr double kMinJudgedTurn = 0.5;
/// Why a truth that turns through `truth_turn` cannot be the truth of rates that turn through
/// `rates_turn` (rad, each summed over the same steps), or nothing.
std::optional<std::string> turnMismatch(double truth_turn, double rates_turn);

/// A truth quaternion is a rotation when its norm is 1 within this (messages carry it in
/// doubles; a float32 source gives about 1e-7).
constexpr double kUnitTolerance = 1e-3;

/// Intervals between consecutive samples: their mean and standard deviation (the jitter).
struct IntervalStats {
  std::uint64_t n = 0;
  double mean = 0.0, m2 = 0.0;  // Welford
  void add(double dt) {
    ++n;
    const double d = dt - mean;
    mean += d / double(n);
    m2 += d * (dt - mean);
  }
  double sd() const { return n > 1 ? std::sqrt(m2 / double(n - 1)) : 0.0; }
};

}  // namespace tools
}  // namespace attitude_propagator
