// The exact torque-free motion against published values (Hairer-Lubich-Wanner's free body,
// docs/numerics.md §8), closed forms (period of the Dzhanibekov flip) and an independent tight
// numerical reference: Boost.Odeint's Bulirsch-Stoer at 1e-14 on the Euler equations written
// with the full inertia tensor in the user's frame (no principal axes, no sorting).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include <boost/math/special_functions/ellint_1.hpp>
#include <boost/numeric/odeint.hpp>

#include "attitude_propagator/torque_free_motion.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;

namespace {

using Ignore = ap::RigidBody::TriangleInequality;

/// Bulirsch-Stoer on (q, w) in long double with I_B full: I dw/dt = (I w) x w,
/// dq/dt = 1/2 q (x) (0, w). Long double, because near the separatrix a double reference at
/// 1e-14 drifts in energy by 1e-14, which moves the flip times by 1e-8 s (measured).
class TensorReference {
 public:
  TensorReference(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0)
      : I_(I_B.cast<Real>()), I_inv_(I_B.cast<Real>().inverse()) {
    x_ = {x0.q_WB.w(), x0.q_WB.x(), x0.q_WB.y(), x0.q_WB.z(), x0.w_B.x(), x0.w_B.y(), x0.w_B.z()};
  }

  ap::DynamicState advanceTo(double t) {
    namespace odeint = boost::numeric::odeint;
    auto system = [this](const State& x, State& dxdt, Real) {
      const Vector w(x[4], x[5], x[6]);
      const Vector v(x[1], x[2], x[3]);
      const Vector dv = Real(0.5) * (x[0] * w + v.cross(w));
      const Vector dw = I_inv_ * Vector(I_ * w).cross(w);
      dxdt = {Real(-0.5) * v.dot(w), dv.x(), dv.y(), dv.z(), dw.x(), dw.y(), dw.z()};
    };
    if (t > t_) {
      odeint::bulirsch_stoer<State, Real> stepper(1e-17L, 1e-17L);
      odeint::integrate_adaptive(stepper, system, x_, Real(t_), Real(t), Real(1e-3));
      t_ = t;
    }
    ap::DynamicState x;
    x.q_WB =
        Eigen::Quaterniond(double(x_[0]), double(x_[1]), double(x_[2]), double(x_[3])).normalized();
    x.w_B = Eigen::Vector3d(double(x_[4]), double(x_[5]), double(x_[6]));
    return x;
  }

 private:
  using Real = long double;
  using State = std::array<Real, 7>;
  using Vector = Eigen::Matrix<Real, 3, 1>;
  Eigen::Matrix<Real, 3, 3> I_;
  Eigen::Matrix<Real, 3, 3> I_inv_;
  State x_;
  double t_ = 0.0;
};

/// Compares the exact motion with the reference every `every` seconds up to t_end.
void expectMatchesReference(const ap::RigidBody& body, const ap::DynamicState& x0, double t_end,
                            double tol, double every = 5.0) {
  const ap::TorqueFreeMotion exact(body, x0);
  TensorReference reference(body.tensor_B(), x0);
  double worst_q = 0.0;
  double worst_w = 0.0;
  for (double t = 0.0; t <= t_end + 1e-9; t += every) {
    const ap::DynamicState a = exact.evaluate(t);
    const ap::DynamicState b = reference.advanceTo(t);
    worst_q = std::max(worst_q, ap::rotationAngle(a.q_WB, b.q_WB));
    worst_w = std::max(worst_w, (a.w_B - b.w_B).norm() / std::max(1.0, x0.w_B.norm()));
  }
  EXPECT_LE(worst_q, tol) << "attitude error (rad)";
  EXPECT_LE(worst_w, tol) << "relative rate error";
}

ap::DynamicState stateWithMomentum(const ap::RigidBody& body, const Eigen::Vector3d& M_B,
                                   const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  ap::DynamicState x;
  x.q_WB = q;
  x.w_B = body.tensor_B().inverse() * M_B;
  return x;
}

}  // namespace

// docs/numerics.md §8: I = (2, 1, 2/3), M0 = (cos 1.1, 0, sin 1.1). Their body frame is ours (P =
// B), so M(t) compares component by component.
TEST(DynTorqueFree, HairerLubichWannerPublishedValues) {
  const ap::RigidBody body =
      ap::RigidBody::fromPrincipalMoments({2.0, 1.0, 2.0 / 3.0}, Ignore::Ignore);
  const ap::DynamicState x0 =
      stateWithMomentum(body, Eigen::Vector3d(std::cos(1.1), 0.0, std::sin(1.1)));
  const ap::TorqueFreeMotion motion(body, x0);
  EXPECT_EQ(motion.form(), ap::TorqueFreeMotion::Form::Triaxial);
  EXPECT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::AboutSmallest);  // their 3rd axis
  EXPECT_NEAR(motion.modulus(), 0.508968105239, 1e-12);
  EXPECT_NEAR(std::abs(motion.lambda()), 0.630178767743, 1e-12);
  EXPECT_NEAR(motion.bodyPeriod(), 10.731465234882, 1e-11);

  const Eigen::Vector3d M10 = body.angularMomentum_B(motion.evaluate(10.0).w_B);
  const Eigen::Vector3d M100 = body.angularMomentum_B(motion.evaluate(100.0).w_B);
  EXPECT_NEAR((M10 - Eigen::Vector3d(0.407066136588041, 0.283007426812843, 0.868449167661562))
                  .cwiseAbs()
                  .maxCoeff(),
              0.0, 1e-13);
  EXPECT_NEAR((M100 - Eigen::Vector3d(-0.177348313874983, -0.590418524333421, 0.787371285791935))
                  .cwiseAbs()
                  .maxCoeff(),
              0.0, 1e-13);
}

TEST(DynTorqueFree, FreeBodyMatchesReference) {
  const ap::RigidBody body =
      ap::RigidBody::fromPrincipalMoments({2.0, 1.0, 2.0 / 3.0}, Ignore::Ignore);
  std::uint64_t seed = 3;
  expectMatchesReference(body,
                         stateWithMomentum(body, Eigen::Vector3d(std::cos(1.1), 0.0, std::sin(1.1)),
                                           randomUnitQuaternion(seed)),
                         100.0, 1e-10);
}

TEST(DynTorqueFree, BothSidesOfTheSeparatrixMatchReference) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 5;
  // Delta2 = M3^2/3 - M1^2: negative about e1 (case i), positive about e3 (case ii).
  const ap::DynamicState about_smallest =
      stateWithMomentum(body, {1.0, 0.3, 0.4}, randomUnitQuaternion(seed));
  const ap::DynamicState about_largest =
      stateWithMomentum(body, {-0.2, 0.5, -1.0}, randomUnitQuaternion(seed));
  EXPECT_EQ(ap::TorqueFreeMotion(body, about_smallest).regime(),
            ap::TorqueFreeMotion::Regime::AboutSmallest);
  EXPECT_EQ(ap::TorqueFreeMotion(body, about_largest).regime(),
            ap::TorqueFreeMotion::Regime::AboutLargest);
  expectMatchesReference(body, about_smallest, 100.0, 1e-10);
  expectMatchesReference(body, about_largest, 100.0, 1e-10);
}

TEST(DynTorqueFree, NearTheSeparatrixMatchesReference) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 11;
  for (const double side : {-1.0, 1.0}) {
    // Delta2 = M3^2/3 - M1^2 = side * 1e-6 relative.
    const double M1 = 0.5;
    const double M3 = std::sqrt(3.0) * M1 * std::sqrt(1.0 + side * 1e-6);
    const ap::DynamicState x0 = stateWithMomentum(body, {M1, 1.0, M3}, randomUnitQuaternion(seed));
    SCOPED_TRACE(side);
    expectMatchesReference(body, x0, 100.0, 1e-10, 2.5);
  }
}

TEST(DynTorqueFree, OnTheSeparatrixMatchesReference) {
  // I = (1, 3, 6), w = (0.75, 0.2, 0.25): Delta2 = I3 I32 w3^2 - I1 I21 w1^2 = 18 w3^2 -
  // 2 w1^2 = 0 exactly.
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 3.0, 6.0}, Ignore::Ignore);
  std::uint64_t seed = 17;
  ap::DynamicState x0;
  x0.q_WB = randomUnitQuaternion(seed);
  x0.w_B = Eigen::Vector3d(0.75, 0.2, 0.25);
  const ap::TorqueFreeMotion motion(body, x0);
  EXPECT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::Separatrix);
  // The separatrix is unstable: perturbations of 1e-16 grow like exp(lambda t), so compare
  // while lambda t stays below ~12.
  expectMatchesReference(body, x0, 10.0 / motion.lambda() * 1.2, 1e-10, 1.0);
}

TEST(DynTorqueFree, SymmetricTopSphereAndTensorMatchReference) {
  std::uint64_t seed = 23;
  const ap::RigidBody prolate = ap::RigidBody::fromPrincipalMoments({2.0, 2.0, 1.0});
  const ap::RigidBody oblate = ap::RigidBody::fromPrincipalMoments({3.0, 2.0, 3.0});
  const ap::RigidBody sphere = ap::RigidBody::fromPrincipalMoments({1.5, 1.5, 1.5});
  EXPECT_EQ(ap::TorqueFreeMotion(prolate, {}).form(), ap::TorqueFreeMotion::Form::SymmetricTop);
  EXPECT_EQ(ap::TorqueFreeMotion(sphere, {}).form(), ap::TorqueFreeMotion::Form::Sphere);
  expectMatchesReference(prolate,
                         stateWithMomentum(prolate, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-10);
  expectMatchesReference(oblate,
                         stateWithMomentum(oblate, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-10);
  expectMatchesReference(sphere,
                         stateWithMomentum(sphere, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-10);
  // A full tensor: principal axes rotated away from the body axes.
  const Eigen::Matrix3d R = randomUnitQuaternion(seed).toRotationMatrix();
  const Eigen::Matrix3d I_B = R * Eigen::Vector3d(1.0, 2.5, 3.0).asDiagonal() * R.transpose();
  const ap::RigidBody tensor = ap::RigidBody::fromTensor(I_B);
  expectMatchesReference(tensor,
                         stateWithMomentum(tensor, {0.7, 0.2, -0.5}, randomUnitQuaternion(seed)),
                         100.0, 1e-10);
}

// The Dzhanibekov flip: started near the middle axis, M2 changes sign every half body period
// 2K(k)/|lambda|, with K from its own definition (Boost's ellint_1 of k).
TEST(DynTorqueFree, DzhanibekovFlipPeriod) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  const ap::DynamicState x0 = stateWithMomentum(body, {1e-3, 1.0, 2e-3});
  const ap::TorqueFreeMotion motion(body, x0);
  const double k = motion.modulus();
  const double period = 4.0 * boost::math::ellint_1(k) / std::abs(motion.lambda());
  EXPECT_NEAR(motion.bodyPeriod(), period, 1e-9 * period);
  // M2 returns to its value after a period, and is at its opposite after half a period
  // (M2 = -B sn(u) with sn(u + 2K) = -sn(u)).
  const double M2_0 = body.angularMomentum_B(x0.w_B).y();
  EXPECT_NEAR(body.angularMomentum_B(motion.evaluate(period).w_B).y(), M2_0, 1e-9);
  EXPECT_NEAR(body.angularMomentum_B(motion.evaluate(0.5 * period).w_B).y(), -M2_0, 1e-9);
  EXPECT_NEAR(body.angularMomentum_B(motion.evaluate(7.5 * period).w_B).y(), -M2_0, 1e-8);
}

// Evaluations far ahead cost the same and stay consistent: the state at t2 from the motion
// through the state at t1 equals the state at t2 directly.
TEST(DynTorqueFree, RestartingFromAnEvaluatedStateIsConsistent) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 29;
  const ap::DynamicState x0 = stateWithMomentum(body, {1.0, 0.3, 0.4}, randomUnitQuaternion(seed));
  const ap::TorqueFreeMotion motion(body, x0);
  const ap::DynamicState x1 = motion.evaluate(1234.5);
  const ap::TorqueFreeMotion restarted(body, x1, 1234.5);
  const ap::DynamicState a = motion.evaluate(1300.0);
  const ap::DynamicState b = restarted.evaluate(1300.0);
  EXPECT_ROTATION_NEAR(a.q_WB, b.q_WB, 1e-11);
  EXPECT_NEAR((a.w_B - b.w_B).norm(), 0.0, 1e-12);
}
