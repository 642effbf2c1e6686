// The absolute-fix path against the filter written out in the test (docs/numerics.md §7, §7.1,
// docs/design.md §6.9): one step of the error state (dtheta_B, db) as P <- F P F^T + Q in 6 x 6,
// a fix between two rate samples as the update made at its own stamp (the error state carried
// there through the motion D and back), and two fixes in one rate interval as two such updates in
// stamp order, whether they arrive on time or late. Everything breaks symmetry: anisotropic,
// correlated covariances (rate, fix and prior), a generic initial attitude, rates about no axis,
// fixes at generic fractions of an interval whose rotation is 0.1 rad.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "engine_fixtures.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::aboutAxis;
using engine_fixtures::at;
using engine_fixtures::Recorder;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

constexpr double kH = 0.04;           // s: 25 Hz rates, a step turns about 0.1 rad
constexpr double kBiasStddev = 0.02;  // rad/s, the prior
constexpr double kBiasWalk = 0.003;   // rad/s/sqrt(s): sigma_b^2 h is visible beside P_bb

// Rates about no fixed axis, none of them small.
Eigen::Vector3d bodyRate(double t) {
  return {1.3 + 0.4 * std::sin(3.0 * t), -2.1 + 0.5 * std::cos(2.0 * t), 0.9 + 0.7 * t};
}

Eigen::Matrix3d fromFactor(double a, double b, double c, double d, double e, double f) {
  Eigen::Matrix3d L;
  L << a, 0.0, 0.0, b, c, 0.0, d, e, f;
  return L * L.transpose();
}

// Each sample's own covariance ((rad/s)^2): anisotropic, correlated, a little different each time.
Eigen::Matrix3d rateCovariance(int k) {
  return (1.0 + 0.1 * k) * fromFactor(0.03, 0.012, 0.018, -0.02, 0.007, 0.01);
}

ap::Input rateSample(int k) {
  ap::Input in;
  in.source = ap::Source::Imu;
  in.stamp = at(kH * k);
  in.value = bodyRate(kH * k);
  in.rate_covariance_B = rateCovariance(k);
  return in;
}

const Eigen::Quaterniond kInitial = aboutAxis(Eigen::Vector3d(0.3, -0.8, 0.5), 0.7);

// exp2 (its step is numerics.md §2's closed form), fuse, every covariance from the inputs.
ap::EngineConfig contractConfig(bool estimate_bias) {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.integrator = ap::Integrator::Exp2;
  c.kinematic.initial_q_WB = kInitial;
  c.initial_orientation_stddev = 0.04;
  c.fixes.mode = ap::FixMode::Fuse;
  c.fixes.estimate_gyro_bias = estimate_bias;
  c.fixes.gyro_bias_stddev = kBiasStddev;
  c.fixes.gyro_bias_random_walk = kBiasWalk;
  return c;
}

// The first fix, at the anchor (it starts the history): its covariance makes P_B anisotropic
// before any step.
const Eigen::Matrix3d kFirstFixCovariance = fromFactor(0.02, -0.01, 0.035, 0.015, 0.012, 0.008);
const Eigen::Vector3d kFirstFixOffset(0.011, -0.023, 0.017);

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// J_r(phi) = I - ((1 - cos t) / t^2) [phi]x + ((t - sin t) / t^3) [phi]x^2 (numerics.md §7);
// every angle here is far above the series' range.
Eigen::Matrix3d rightJacobianOf(const Eigen::Vector3d& phi) {
  const double t = phi.norm();
  const Eigen::Matrix3d K = skew(phi);
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(t)) / (t * t) * K +
         (t - std::sin(t)) / (t * t * t) * K * K;
}

// The filter of numerics.md §7.1 in one 6 x 6 covariance: the true attitude q (x) Exp(dtheta_B),
// the true bias b + db. Without the bias estimate its bias blocks are zero and stay so.
struct Reference {
  Eigen::Quaterniond q;
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  Matrix6 P = Matrix6::Zero();
  double sigma_b = 0.0;  // the bias' random walk, 0 without the estimate

  Eigen::Matrix3d P_B() const { return P.topLeftCorner<3, 3>(); }
  Eigen::Vector3d biasStddev() const { return P.bottomRightCorner<3, 3>().diagonal().cwiseSqrt(); }

  // A step of rotation `step` over h with the sample's covariance R: F = [Phi, -G; 0, I],
  // Phi = C(step)^T, G = h J_r(Log step), Q = diag(G R G^T, sigma_b^2 h I), P <- F P F^T + Q.
  void propagate(const Eigen::Quaterniond& step, double h, const Eigen::Matrix3d& R) {
    const Eigen::Vector3d phi = ap::logMap(step);
    const Eigen::Matrix3d G = h * rightJacobianOf(phi);
    Matrix6 F = Matrix6::Identity();
    F.topLeftCorner<3, 3>() = step.toRotationMatrix().transpose();
    F.topRightCorner<3, 3>() = -G;
    Matrix6 Q = Matrix6::Zero();
    Q.topLeftCorner<3, 3>() = G * R * G.transpose();
    Q.bottomRightCorner<3, 3>() = sigma_b * sigma_b * h * Eigen::Matrix3d::Identity();
    P = F * P * F.transpose() + Q;
    q = q * step;
  }

  // A fix (q_fix, R) at this instant: H = [I 0], r = Log(q^-1 q_fix), S = P_thth + R,
  // K = P H^T S^-1, q <- q (x) Exp(dx_th), b <- b + dx_b, P in the Joseph form.
  void fuse(const Eigen::Quaterniond& q_fix, const Eigen::Matrix3d& R) {
    Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
    H.leftCols<3>().setIdentity();
    const Eigen::Vector3d r = ap::logMap(q.conjugate() * q_fix);
    const Eigen::Matrix3d S = H * P * H.transpose() + R;
    const Eigen::Matrix<double, 6, 3> K = P * H.transpose() * S.inverse();
    const Eigen::Matrix<double, 6, 1> dx = K * r;
    q = q * ap::expMap(dx.head<3>());
    b += dx.tail<3>();
    const Matrix6 I_KH = Matrix6::Identity() - K * H;
    P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
  }

  // The same state seen D further along the motion: q <- q (x) D, and an error there is the
  // error here turned by D, dtheta <- C(D)^T dtheta (design.md §6.9); the bias error stays.
  void move(const Eigen::Quaterniond& D) {
    Matrix6 T = Matrix6::Identity();
    T.topLeftCorner<3, 3>() = D.toRotationMatrix().transpose();
    P = T * P * T.transpose();
    q = q * D;
  }

  // A fix at the fraction a of the interval to the state q_next: the estimate there is
  // q (x) D, D = Exp(a Log(q^-1 q_next)); the update is made there and carried back.
  void fuseBetween(const Eigen::Quaterniond& q_next, double a, const Eigen::Quaterniond& q_fix,
                   const Eigen::Matrix3d& R) {
    const Eigen::Quaterniond D = ap::expMap(a * ap::logMap(q.conjugate() * q_next));
    move(D);
    fuse(q_fix, R);
    move(D.conjugate());
  }
};

// exp2's step from sample k - 1 to k, each rate less the bias estimate subtracted when the
// model took it (design.md §6.9: a replayed rate takes the estimate as it is then).
Eigen::Quaterniond exp2Step(int k, const Eigen::Vector3d& bias_before,
                            const Eigen::Vector3d& bias_after) {
  const Eigen::Vector3d w0 = bodyRate(kH * (k - 1)) - bias_before;
  const Eigen::Vector3d w1 = bodyRate(kH * k) - bias_after;
  return ap::expMap(0.5 * kH * (w0 + w1));
}

double largest(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

// The engine's state against the reference: attitude, P_B, bias estimate and its deviation.
void expectState(const ap::EngineState& s, const Reference& x, bool estimate_bias) {
  EXPECT_LE(ap::rotationAngle(s.q_WB, x.q), 1e-12);
  EXPECT_LE(largest(s.P_B - x.P_B()), 1e-12 * largest(x.P_B())) << "engine\n"
                                                                << s.P_B << "\nreference\n"
                                                                << x.P_B();
  if (!estimate_bias) return;
  EXPECT_LE((s.gyro_bias_estimate_B - x.b).norm(), 1e-12 * kBiasStddev)
      << s.gyro_bias_estimate_B.transpose() << " vs " << x.b.transpose();
  EXPECT_LE((s.gyro_bias_stddev_B - x.biasStddev()).norm(), 1e-12 * kBiasStddev)
      << s.gyro_bias_stddev_B.transpose() << " vs " << x.biasStddev().transpose();
}

// The anchor at sample 0 and the first fix there: the reference's start, checked.
Reference start(ap::AttitudeEngine& engine, bool estimate_bias) {
  Reference x;
  x.q = kInitial;
  x.P.topLeftCorner<3, 3>() = 0.04 * 0.04 * Eigen::Matrix3d::Identity();
  if (estimate_bias) {
    x.P.bottomRightCorner<3, 3>() = kBiasStddev * kBiasStddev * Eigen::Matrix3d::Identity();
    x.sigma_b = kBiasWalk;
  }
  engine.submit(rateSample(0));
  const Eigen::Quaterniond q_fix = kInitial * ap::expMap(kFirstFixOffset);
  EXPECT_EQ(engine.submitFix(at(0.0), q_fix, kFirstFixCovariance), ap::FixOutcome::Accepted);
  x.fuse(q_fix, kFirstFixCovariance);
  expectState(engine.state(), x, estimate_bias);
  return x;
}

// Samples first..last, the reference stepped with each (no fix in between, so the bias estimate
// is the same before and after).
void stepTo(ap::AttitudeEngine& engine, Reference& x, int first, int last) {
  for (int k = first; k <= last; ++k) {
    engine.submit(rateSample(k));
    x.propagate(exp2Step(k, x.b, x.b), kH, rateCovariance(k));
  }
}

// ---- one step of the error state -------------------------------------------------------------

// numerics.md §7.1: each step maps P by F P F^T + Q with F = [Phi, -G; 0, I], Phi = C(Exp(h w))^T,
// G = h J_r(h w), Q = diag(G R G^T, sigma_b^2 h I), from a state the test knows in full (the
// anchor's prior, a fix with a correlated covariance, then each step before): P_B and the bias'
// deviation after every step. The cross-covariance P_thb is read through what it does: it enters
// P_B from the second step on, and a fix at the newest state moves the bias estimate by
// P_bth S^-1 r.
TEST(FixContracts, EachStepOfTheErrorStateIsFPFTransposedPlusQ) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    Recorder sink;
    ap::AttitudeEngine engine(contractConfig(estimate_bias), sink);
    Reference x = start(engine, estimate_bias);
    for (int k = 1; k <= 6; ++k) {
      SCOPED_TRACE(k);
      stepTo(engine, x, k, k);
      const ap::EngineState* s = sink.stateAt(at(kH * k));
      ASSERT_NE(s, nullptr);
      expectState(*s, x, estimate_bias);
    }
    // The cross-covariance is far from negligible beside P_B: its terms are there to be seen.
    if (estimate_bias) {
      EXPECT_GT(largest(x.P.topRightCorner<3, 3>()), 0.01 * largest(x.P_B()));
    }
    // A fix at the newest state (no motion to carry it through): the bias estimate moves by
    // P_bth S^-1 r, which the sign and size of P_thb decide.
    const Eigen::Matrix3d R = fromFactor(0.015, 0.008, 0.02, -0.012, -0.004, 0.025);
    const Eigen::Quaterniond q_fix = x.q * ap::expMap(Eigen::Vector3d(-0.013, 0.019, 0.008));
    ASSERT_EQ(engine.submitFix(at(kH * 6), q_fix, R), ap::FixOutcome::Accepted);
    const Eigen::Vector3d bias_before = x.b;
    x.fuse(q_fix, R);
    expectState(engine.state(), x, estimate_bias);
    if (estimate_bias) {
      EXPECT_GT((x.b - bias_before).norm(), 1e-4);  // it does move
    }
  }
}

// ---- a fix between two samples ---------------------------------------------------------------

constexpr int kBefore = 12;  // the fixes fall between samples 12 and 13 (t = 0.48 s, 0.52 s)
constexpr int kLateAt = 20;  // a late fix is handed in after sample 20, 0.28 s late
constexpr int kLastSample = 24;

struct BetweenFix {
  double a;  // where in the interval [kBefore, kBefore + 1]
  Eigen::Matrix3d R;
  Eigen::Vector3d offset;  // from the estimate interpolated to its stamp
};

ap::Stamp stampOf(const BetweenFix& f) { return at(kH * (kBefore + f.a)); }

// Two fixes in one interval, each with a covariance correlated its own way.
const BetweenFix kFirstBetween{0.37, fromFactor(0.012, 0.02, 0.025, -0.006, -0.01, 0.03),
                               Eigen::Vector3d(0.009, 0.014, -0.011)};
const BetweenFix kSecondBetween{0.81, fromFactor(0.03, -0.015, 0.01, 0.004, 0.02, 0.018),
                                Eigen::Vector3d(-0.012, 0.006, 0.016)};
// A third between the two, and one far off the estimate, which the gate rejects.
const BetweenFix kThirdBetween{0.59, fromFactor(0.02, 0.01, 0.03, -0.012, 0.005, 0.022),
                               Eigen::Vector3d(0.007, -0.013, 0.01)};
const BetweenFix kFarOffBetween{0.2, fromFactor(0.01, 0.0, 0.01, 0.0, 0.0, 0.01),
                                Eigen::Vector3d(0.4, -0.3, 0.2)};

// The fixes' attitudes: the estimate at their stamps (the states at samples kBefore and
// kBefore + 1 as a run without them has them, interpolated along the geodesic) turned by their
// offsets; the same quaternions in every run.
std::vector<Eigen::Quaterniond> fixAttitudes(bool estimate_bias,
                                             const std::vector<BetweenFix>& fixes) {
  Recorder sink;
  ap::AttitudeEngine engine(contractConfig(estimate_bias), sink);
  Reference x = start(engine, estimate_bias);
  stepTo(engine, x, 1, kBefore + 1);
  const Eigen::Quaterniond q_k = sink.stateAt(at(kH * kBefore))->q_WB;
  const Eigen::Vector3d motion = ap::logMap(q_k.conjugate() * engine.state().q_WB);
  std::vector<Eigen::Quaterniond> q;
  for (const BetweenFix& f : fixes)
    q.push_back(q_k * ap::expMap(f.a * motion) * ap::expMap(f.offset));
  return q;
}

// Runs samples 0..kLastSample with the first fix at the anchor and `fixes` handed in, in the
// order given, after sample `hand_in`, each expected to have the outcome `outcomes` gives it.
// Returns the newest state right after they were handed in (`then`) and at the end.
ap::EngineState runHandedIn(bool estimate_bias, const std::vector<BetweenFix>& fixes,
                            const std::vector<Eigen::Quaterniond>& q_fixes,
                            const std::vector<ap::FixOutcome>& outcomes, int hand_in,
                            ap::EngineState* then = nullptr) {
  Recorder sink;
  ap::AttitudeEngine engine(contractConfig(estimate_bias), sink);
  start(engine, estimate_bias);
  for (int k = 1; k <= kLastSample; ++k) {
    engine.submit(rateSample(k));
    if (k != hand_in) continue;
    for (std::size_t i = 0; i < fixes.size(); ++i) {
      EXPECT_EQ(engine.submitFix(stampOf(fixes[i]), q_fixes[i], fixes[i].R), outcomes[i]) << i;
    }
    if (then != nullptr) *then = engine.state();
  }
  const auto accepted = std::count(outcomes.begin(), outcomes.end(), ap::FixOutcome::Accepted);
  EXPECT_EQ(engine.counters().fixes_accepted, 1u + static_cast<std::uint64_t>(accepted));
  EXPECT_TRUE(sink.stampsIncrease());
  return engine.state();
}

// The same, every fix accepted.
ap::EngineState runBetween(bool estimate_bias, const std::vector<BetweenFix>& fixes,
                           const std::vector<Eigen::Quaterniond>& q_fixes, int hand_in,
                           ap::EngineState* then = nullptr) {
  const std::vector<ap::FixOutcome> accepted(fixes.size(), ap::FixOutcome::Accepted);
  return runHandedIn(estimate_bias, fixes, q_fixes, accepted, hand_in, then);
}

// design.md §6.9: a fix between samples k and k + 1 is compared with the estimate interpolated
// along the geodesic, q_f = q_k (x) D; the error state is carried there (dtheta_f = C(D)^T
// dtheta_k), updated, and carried back; then the step to k + 1 is taken again, with the bias
// estimate as the fix left it. The reference does each of those in 6 x 6 from the state at k it
// knows; the fix's covariance is correlated and the interval turns 0.1 rad about no axis, so C R
// C^T and C^T R C, or a cross-covariance turned the wrong way, differ far beyond round-off.
TEST(FixContracts, AFixBetweenTwoSamplesIsTheUpdateAtItsStampCarriedBack) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    const std::vector<BetweenFix> fixes{kFirstBetween};
    const std::vector<Eigen::Quaterniond> q_fix = fixAttitudes(estimate_bias, fixes);
    Recorder sink;
    ap::AttitudeEngine engine(contractConfig(estimate_bias), sink);
    Reference x = start(engine, estimate_bias);
    stepTo(engine, x, 1, kBefore);
    const Reference at_k = x;
    stepTo(engine, x, kBefore + 1, kBefore + 1);
    expectState(engine.state(), x, estimate_bias);
    // On time: handed in with the sample after its stamp.
    ASSERT_EQ(engine.submitFix(stampOf(kFirstBetween), q_fix[0], kFirstBetween.R),
              ap::FixOutcome::Accepted);
    Reference y = at_k;
    y.fuseBetween(x.q, kFirstBetween.a, q_fix[0], kFirstBetween.R);
    y.propagate(exp2Step(kBefore + 1, at_k.b, y.b), kH, rateCovariance(kBefore + 1));
    expectState(engine.state(), y, estimate_bias);
    // The inputs tell the two frames apart: the covariance at k turned by C(D)^T and by C(D)
    // differ by far more than the tolerances.
    const Eigen::Matrix3d C =
        ap::expMap(kFirstBetween.a * ap::logMap(at_k.q.conjugate() * x.q)).toRotationMatrix();
    EXPECT_GT(largest(C.transpose() * at_k.P_B() * C - C * at_k.P_B() * C.transpose()),
              1e-3 * largest(at_k.P_B()));
    // Late (0.28 s, seven states replayed): the newest state is the on-time one.
    const ap::EngineState on_time = runBetween(estimate_bias, fixes, q_fix, kBefore + 1);
    const ap::EngineState late = runBetween(estimate_bias, fixes, q_fix, kLateAt);
    EXPECT_LE(ap::rotationAngle(late.q_WB, on_time.q_WB), 1e-12);
    EXPECT_LE(largest(late.P_B - on_time.P_B), 1e-12 * largest(on_time.P_B));
    EXPECT_LE((late.gyro_bias_estimate_B - on_time.gyro_bias_estimate_B).norm(), 1e-14);
  }
}

// ---- two fixes in one interval ---------------------------------------------------------------

// Both fixes between the same two samples, handed in on time (with the sample after them, in
// stamp order): the first is the update at its stamp carried back and the step taken again, the
// second the same from the state the first left, interpolated towards the next state as the
// first left it. Late and in order (0.28 s) the newest state is the on-time one.
TEST(FixContracts, TwoFixesInOneIntervalAreTwoUpdatesInStampOrder) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    const std::vector<BetweenFix> fixes{kFirstBetween, kSecondBetween};
    const std::vector<Eigen::Quaterniond> q_fix = fixAttitudes(estimate_bias, fixes);
    Recorder sink;
    ap::AttitudeEngine engine(contractConfig(estimate_bias), sink);
    Reference x = start(engine, estimate_bias);
    stepTo(engine, x, 1, kBefore);
    const Reference at_k = x;
    stepTo(engine, x, kBefore + 1, kBefore + 1);
    Reference y = at_k;    // at sample kBefore, each fix carried back into it
    Reference newest = x;  // at sample kBefore + 1, the step taken again after each fix
    for (std::size_t i = 0; i < fixes.size(); ++i) {
      SCOPED_TRACE(i);
      ASSERT_EQ(engine.submitFix(stampOf(fixes[i]), q_fix[i], fixes[i].R),
                ap::FixOutcome::Accepted);
      y.fuseBetween(newest.q, fixes[i].a, q_fix[i], fixes[i].R);
      newest = y;
      newest.propagate(exp2Step(kBefore + 1, at_k.b, y.b), kH, rateCovariance(kBefore + 1));
      expectState(engine.state(), newest, estimate_bias);
    }
    // The runs compared below: on time it is the reference's state too.
    ap::EngineState then;
    const ap::EngineState on_time = runBetween(estimate_bias, fixes, q_fix, kBefore + 1, &then);
    expectState(then, newest, estimate_bias);
    const ap::EngineState late = runBetween(estimate_bias, fixes, q_fix, kLateAt);
    EXPECT_LE(ap::rotationAngle(late.q_WB, on_time.q_WB), 1e-12);
    EXPECT_LE(largest(late.P_B - on_time.P_B), 1e-12 * largest(on_time.P_B));
    EXPECT_LE((late.gyro_bias_estimate_B - on_time.gyro_bias_estimate_B).norm(), 1e-14);
    // The second fix matters: with the first alone the newest state differs by far more.
    const std::vector<BetweenFix> first_only{kFirstBetween};
    const ap::EngineState one = runBetween(estimate_bias, first_only, {q_fix[0]}, kBefore + 1);
    EXPECT_GT(ap::rotationAngle(one.q_WB, on_time.q_WB), 1e-3);
  }
}

// design.md §6.9 promises the on-time state for fixes out of order, also for two fixes in one
// interval handed in the later first. Applying a fix replaces the entry it acts at (the state at
// the sample before it) by the corrected one; the earlier fix must act at that entry as it was
// without the later one, or the later fix, applied again after it, counts twice (before the
// engine kept the entries as they were: the attitude 2.5 mrad from the on-time one with the
// bias estimated, 1.4 mrad with the attitude alone, P_B's trace 8 % and 9 % low).
TEST(FixContracts, TwoFixesInOneIntervalHandedInReversedAreTheOnTimeOnes) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    const std::vector<BetweenFix> fixes{kFirstBetween, kSecondBetween};
    const std::vector<Eigen::Quaterniond> q_fix = fixAttitudes(estimate_bias, fixes);
    const ap::EngineState on_time = runBetween(estimate_bias, fixes, q_fix, kBefore + 1);
    const ap::EngineState reversed =
        runBetween(estimate_bias, {kSecondBetween, kFirstBetween}, {q_fix[1], q_fix[0]}, kLateAt);
    std::printf(
        "[ fixes    ] reversed in one interval: %.3g rad from on time, trace P_B %.4g "
        "against %.4g\n",
        ap::rotationAngle(reversed.q_WB, on_time.q_WB), reversed.P_B.trace(), on_time.P_B.trace());
    EXPECT_LE(ap::rotationAngle(reversed.q_WB, on_time.q_WB), 1e-12);
    EXPECT_LE(largest(reversed.P_B - on_time.P_B), 1e-12 * largest(on_time.P_B));
  }
}

// Three in one interval handed in latest first: when the earliest arrives, the two applied after
// it each changed the entry it acts at; set back latest first, the entry is as it was before
// both (set back in the other order, it would keep the middle one's correction, which would
// then count twice).
TEST(FixContracts, ThreeFixesInOneIntervalHandedInLatestFirstAreTheOnTimeOnes) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    const std::vector<BetweenFix> fixes{kFirstBetween, kThirdBetween, kSecondBetween};
    const std::vector<Eigen::Quaterniond> q = fixAttitudes(estimate_bias, fixes);
    const ap::EngineState on_time = runBetween(estimate_bias, fixes, q, kBefore + 1);
    const ap::EngineState reversed = runBetween(
        estimate_bias, {kSecondBetween, kThirdBetween, kFirstBetween}, {q[2], q[1], q[0]}, kLateAt);
    EXPECT_LE(ap::rotationAngle(reversed.q_WB, on_time.q_WB), 1e-12);
    EXPECT_LE(largest(reversed.P_B - on_time.P_B), 1e-12 * largest(on_time.P_B));
  }
}

// An earlier fix the gate rejects leaves the entries the applied ones changed as they were: a
// fix in the same interval after them, handed in next, still acts with their corrections, and
// the end is the run without the rejected one.
TEST(FixContracts, ARejectedEarlierFixPutsTheEntriesBack) {
  for (bool estimate_bias : {true, false}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    const std::vector<BetweenFix> all{kFirstBetween, kFarOffBetween, kSecondBetween};
    const std::vector<Eigen::Quaterniond> q = fixAttitudes(estimate_bias, all);
    const ap::EngineState without =
        runBetween(estimate_bias, {kFirstBetween, kSecondBetween}, {q[0], q[2]}, kBefore + 1);
    const ap::EngineState with = runHandedIn(
        estimate_bias, all, q,
        {ap::FixOutcome::Accepted, ap::FixOutcome::RejectedGate, ap::FixOutcome::Accepted},
        kLateAt);
    EXPECT_LE(ap::rotationAngle(with.q_WB, without.q_WB), 1e-12);
    EXPECT_LE(largest(with.P_B - without.P_B), 1e-12 * largest(without.P_B));
  }
}

}  // namespace
