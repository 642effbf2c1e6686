// The quaternion layer against the claims of the Coutsias–Romero notes, checked as
// properties over many random quaternions.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "attitude_propagator/numerics/quaternion.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;

namespace {

constexpr int kTrials = 1000;
constexpr double kEps = std::numeric_limits<double>::epsilon();

class QuaternionProperties : public ::testing::Test {
 protected:
  Eigen::Quaterniond unit() { return randomUnitQuaternion(seed_); }
  // A non-unit quaternion with norm between 0.5 and 2.
  Eigen::Quaterniond scaled() {
    const Eigen::Quaterniond q = unit();
    return Eigen::Quaterniond(q.coeffs() * (0.5 + 1.5 * (unit().w() * 0.5 + 0.5)));
  }
  Eigen::Vector3d vector() { return 3.0 * unit().vec(); }
  std::uint64_t seed_ = 12345;
};

// The rotation matrix A of the notes §6, written out from the coefficients.
Eigen::Matrix3d notesMatrix(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  Eigen::Matrix3d a;
  a << w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z;
  return a;
}

// x = q X q^c computed with quaternion products only (notes eq. 7).
Eigen::Vector3d conjugateBy(const Eigen::Quaterniond& q, const Eigen::Vector3d& v) {
  return (q * ap::pureQuaternion(v) * q.conjugate()).vec();
}

}  // namespace

// |p q| = |p| |q| in the matrix form of the notes §7: L(q)^T L(q) = R(q)^T R(q) = |q|^2 I, with
// |q|^2 the sum of the squared coefficients.
TEST_F(QuaternionProperties, ProductMatricesScaleByTheSquaredNorm) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = scaled();
    const double n2 = q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z();
    const Eigen::Matrix4d expected = n2 * Eigen::Matrix4d::Identity();
    // Measured at most 1.8e-15 (|q|^2 up to 4); bound 16 eps = 3.6e-15.
    EXPECT_LE((ap::leftMatrix(q).transpose() * ap::leftMatrix(q) - expected).norm(), 16 * kEps);
    EXPECT_LE((ap::rightMatrix(q).transpose() * ap::rightMatrix(q) - expected).norm(), 16 * kEps);
  }
}

// q^-1 = q^c / |q|^2 (notes §3): the conjugate written out from the coefficients,
// (w, -x, -y, -z), gives L(q^c) = L(q)^T and R(q^c) = R(q)^T, and q (x) q^c / |q|^2 = 1 from
// either side; the rotation vector of q^c is minus that of q.
TEST_F(QuaternionProperties, InverseIsConjugateOverSquaredNorm) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = scaled();
    const Eigen::Quaterniond conjugate(q.w(), -q.x(), -q.y(), -q.z());
    const double n2 = q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z();
    EXPECT_EQ(ap::leftMatrix(conjugate), ap::leftMatrix(q).transpose());
    EXPECT_EQ(ap::rightMatrix(conjugate), ap::rightMatrix(q).transpose());
    // Measured at most 7.9e-17; bound 2 eps.
    const Eigen::Vector4d one(1, 0, 0, 0);  // (w, x, y, z)
    EXPECT_LE((ap::leftMatrix(q) * ap::wxyz(conjugate) / n2 - one).norm(), 2 * kEps);
    EXPECT_LE((ap::rightMatrix(q) * ap::wxyz(conjugate) / n2 - one).norm(), 2 * kEps);
    const Eigen::Quaterniond u = unit();
    const Eigen::Quaterniond u_conjugate(u.w(), -u.x(), -u.y(), -u.z());
    EXPECT_LE((ap::logMap(u_conjugate) + ap::logMap(u)).norm(), 2 * kEps);
  }
}

TEST_F(QuaternionProperties, ConjugationIsARotation) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = unit();
    const Eigen::Vector3d a = vector(), b = vector();
    const Eigen::Vector3d ra = conjugateBy(q, a), rb = conjugateBy(q, b);
    EXPECT_NEAR(ra.dot(rb), a.dot(b), 32 * kEps);
    EXPECT_LE((ra.cross(rb) - conjugateBy(q, a.cross(b))).norm(), 64 * kEps);
    EXPECT_NEAR(ra.norm(), a.norm(), 16 * kEps);
  }
}

TEST_F(QuaternionProperties, RotationMatrixOfTheNotes) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = unit();
    const Eigen::Vector3d v = vector();
    const Eigen::Matrix3d a = notesMatrix(q);
    EXPECT_LE((a - q.toRotationMatrix()).norm(), 16 * kEps);
    EXPECT_LE((a * v - conjugateBy(q, v)).norm(), 64 * kEps);
    EXPECT_LE((a.transpose() * a - Eigen::Matrix3d::Identity()).norm(), 16 * kEps);
    EXPECT_NEAR(a.determinant(), 1.0, 16 * kEps);
  }
}

TEST_F(QuaternionProperties, QAndMinusQGiveTheSameRotation) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = unit();
    const Eigen::Quaterniond minus_q(-q.coeffs());
    EXPECT_LE((notesMatrix(q) - notesMatrix(minus_q)).norm(), 0.0);
    EXPECT_LE(ap::rotationAngle(q, minus_q), 4 * kEps);
  }
}

// Notes Theorem 6: rotating by q1 and then by q2 is the rotation by q2 q1.
TEST_F(QuaternionProperties, CompositionOfRotations) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q1 = unit(), q2 = unit();
    const Eigen::Vector3d v = vector();
    EXPECT_LE((conjugateBy(q2, conjugateBy(q1, v)) - conjugateBy(q2 * q1, v)).norm(), 64 * kEps);
    EXPECT_LE((notesMatrix(q2 * q1) - notesMatrix(q2) * notesMatrix(q1)).norm(), 32 * kEps);
  }
}

// Notes §5: a quarter turn about x followed by a quarter turn about y, composed in space, is a
// third of a turn about (1, 1, -1)/sqrt(3); composed in body axes, about (1, 1, 1)/sqrt(3).
TEST(Octahedron, QuarterTurnsComposeToAThirdTurn) {
  const double s = std::sqrt(0.5);
  const Eigen::Quaterniond q_x(s, s, 0, 0), q_y(s, 0, s, 0);
  const double third = 2.0 * M_PI / 3.0;
  const Eigen::Vector3d space_axis = Eigen::Vector3d(1, 1, -1) / std::sqrt(3.0);
  const Eigen::Vector3d body_axis = Eigen::Vector3d(1, 1, 1) / std::sqrt(3.0);
  const Eigen::Quaterniond expected_space(std::cos(third / 2), std::sin(third / 2) * space_axis.x(),
                                          std::sin(third / 2) * space_axis.y(),
                                          std::sin(third / 2) * space_axis.z());
  const Eigen::Quaterniond expected_body(std::cos(third / 2), std::sin(third / 2) * body_axis.x(),
                                         std::sin(third / 2) * body_axis.y(),
                                         std::sin(third / 2) * body_axis.z());
  EXPECT_LE(((q_y * q_x).coeffs() - expected_space.coeffs()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE(((q_x * q_y).coeffs() - expected_body.coeffs()).cwiseAbs().maxCoeff(), 1e-15);
  // The octahedron maps to itself: the third turn permutes the coordinate axes.
  const Eigen::Vector3d image = conjugateBy(q_x * q_y, Eigen::Vector3d::UnitX());
  EXPECT_LE((image - Eigen::Vector3d::UnitY()).norm(), 1e-15);
}

TEST_F(QuaternionProperties, LeftAndRightMatrices) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond p = scaled(), q = scaled(), r = scaled();
    const Eigen::Vector4d pq = ap::wxyz(p * q);
    EXPECT_LE((ap::leftMatrix(p) * ap::wxyz(q) - pq).norm(), 32 * kEps);
    EXPECT_LE((ap::rightMatrix(q) * ap::wxyz(p) - pq).norm(), 32 * kEps);
    // Left and right multiplication commute (associativity): L(p) R(r) = R(r) L(p).
    const Eigen::Matrix4d lr = ap::leftMatrix(p) * ap::rightMatrix(r);
    EXPECT_LE((lr - ap::rightMatrix(r) * ap::leftMatrix(p)).norm(), 64 * kEps);
    // For a unit quaternion both are orthogonal.
    const Eigen::Quaterniond u = unit();
    EXPECT_LE(
        (ap::leftMatrix(u).transpose() * ap::leftMatrix(u) - Eigen::Matrix4d::Identity()).norm(),
        16 * kEps);
    EXPECT_LE(
        (ap::rightMatrix(u).transpose() * ap::rightMatrix(u) - Eigen::Matrix4d::Identity()).norm(),
        16 * kEps);
  }
}

// Notes Theorem 2: v' = n v n mirrors v in the plane normal to n; two mirrors make a rotation
// by twice the angle between them.
TEST_F(QuaternionProperties, ReflectionAndTwoReflectionsMakeARotation) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Vector3d n = unit().vec().normalized(), m = unit().vec().normalized();
    const Eigen::Vector3d v = vector();
    const Eigen::Vector3d mirrored = ap::reflect(n, v);
    EXPECT_LE((mirrored - (v - 2.0 * n.dot(v) * n)).norm(), 64 * kEps);
    EXPECT_NEAR(mirrored.norm(), v.norm(), 32 * kEps);
    EXPECT_LE((ap::reflect(n, mirrored) - v).norm(), 64 * kEps);
    // Reflect in n, then in m: the rotation about n x m by twice the angle between them.
    const double half = std::atan2(n.cross(m).norm(), n.dot(m));
    const Eigen::Quaterniond rotation(Eigen::AngleAxisd(2.0 * half, n.cross(m).normalized()));
    EXPECT_LE((ap::reflect(m, ap::reflect(n, v)) - rotation * v).norm(), 256 * kEps);
  }
  EXPECT_THROW(ap::reflect(Eigen::Vector3d(1, 1, 0), Eigen::Vector3d::UnitX()),
               std::invalid_argument);
}

TEST_F(QuaternionProperties, ExpAndLogAreInverse) {
  for (int i = 0; i < kTrials; ++i) {
    const Eigen::Quaterniond q = unit();
    EXPECT_ROTATION_NEAR(ap::expMap(ap::logMap(q)), q, 16 * kEps);
    const Eigen::Vector3d v = unit().vec().normalized() * (M_PI * (i + 0.5) / kTrials);
    EXPECT_LE((ap::logMap(ap::expMap(v)) - v).norm(), 64 * kEps);
    EXPECT_NEAR(ap::expMap(3.0 * vector()).norm(), 1.0, 4 * kEps);
  }
}

TEST(ExpMap, AgreesWithAngleAxisAndHasNoSeamAtTheSeriesBranch) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  for (double angle :
       {0.0, 1e-300, 1e-20, 1e-9, 9.99e-7, 1e-6, 1.01e-6, 1e-3, 1.0, 3.0, M_PI, 10.0, 1000.0}) {
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(angle, axis));
    const Eigen::Quaterniond q = ap::expMap(angle * axis);
    EXPECT_LE((q.coeffs() - expected.coeffs()).cwiseAbs().maxCoeff(), 4 * kEps * (1 + angle))
        << "angle " << angle;
  }
}

TEST(LogMap, EdgeCases) {
  EXPECT_EQ(ap::logMap(Eigen::Quaterniond::Identity()), Eigen::Vector3d::Zero());
  // A tiny rotation keeps its full relative precision.
  const Eigen::Vector3d tiny(1e-12, -2e-12, 3e-12);
  EXPECT_LE((ap::logMap(ap::expMap(tiny)) - tiny).norm(), kEps * tiny.norm());
  // A half turn, from either sign of q.
  const Eigen::Quaterniond half_turn(0.0, 0.0, 0.0, 1.0);
  EXPECT_NEAR(ap::logMap(half_turn).norm(), M_PI, 4 * kEps);
  EXPECT_NEAR(ap::logMap(Eigen::Quaterniond(-half_turn.coeffs())).norm(), M_PI, 4 * kEps);
  // -q gives the same (short) rotation vector as q.
  const Eigen::Quaterniond q = ap::expMap(Eigen::Vector3d(0.4, 0.1, -0.2));
  EXPECT_LE((ap::logMap(Eigen::Quaterniond(-q.coeffs())) - ap::logMap(q)).norm(), 4 * kEps);
}

TEST(RotationAngle, SmallAndLargeAngles) {
  const Eigen::Quaterniond q = ap::expMap(Eigen::Vector3d(0.2, 0.3, -0.1));
  for (double angle : {1e-15, 1e-9, 0.5, 3.0}) {
    const Eigen::Quaterniond r = q * ap::expMap(Eigen::Vector3d(0, 0, angle));
    EXPECT_NEAR(ap::rotationAngle(q, r), angle, 8 * kEps * std::max(1.0, angle));
  }
}
