#include "attitude_propagator/estimation/hard_iron_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace attitude_propagator {

namespace {

constexpr double kMicro = 1e6;  // the sums are kept in uT
constexpr std::uint64_t kMinReads = 5;
// Reads that fix no sphere leave the normal matrix singular to rounding: its smallest
// eigenvalue this far below its largest.
constexpr double kSingular = 1e-12;

}  // namespace

bool HardIronSphere::determined() const {
  return centre_stddev.allFinite() && centre_stddev.maxCoeff() <= kHardIronDetermined &&
         least_spread >= kHardIronSpread * off_rms;
}

void HardIronFit::add(const Eigen::Vector3d& m_B) {
  if (!m_B.allFinite() || m_B.isZero(0.0)) return;  // no read (a driver's NaN or zeros)
  if (m_B.norm() > kMaxFieldRead) return;           // no field: one would outweigh the rest
  const Eigen::Vector3d m = kMicro * m_B;
  Eigen::Vector4d a;
  a << 2.0 * m, 1.0;
  const double y = m.squaredNorm();
  normal_ += a * a.transpose();
  right_ += y * a;
  squares_ += y * y;
  ++n_;
}

std::optional<HardIronSphere> HardIronFit::solve() const {
  if (n_ < kMinReads) return std::nullopt;
  const double n = static_cast<double>(n_);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(normal_);
  const Eigen::Vector4d lambda = eigen.eigenvalues();  // ascending
  if (!(lambda(0) > kSingular * lambda(3))) return std::nullopt;
  const Eigen::Matrix4d inverse =
      eigen.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  const Eigen::Vector4d x = inverse * right_;
  const Eigen::Vector3d c = x.head<3>();
  const double r2 = x(3) + c.squaredNorm();
  if (!(r2 > 0.0)) return std::nullopt;
  // The residuals e = |m|^2 - a.x: sum e^2 = sum |m|^4 - 2 x.right + x^T N x, their variance
  // over n - 4, and the centre's covariance sigma^2 N^-1.
  const double rss = std::max(0.0, squares_ - 2.0 * x.dot(right_) + x.dot(normal_ * x));
  const double sigma2 = rss / (n - 4.0);
  HardIronSphere s;
  s.centre = c / kMicro;
  s.centre_stddev = (sigma2 * inverse.diagonal().head<3>()).cwiseSqrt() / kMicro;
  s.radius = std::sqrt(r2) / kMicro;
  // A read d off the sphere (radially) leaves e = 2 r d to first order.
  s.off_rms = std::sqrt(rss / n) / (2.0 * std::sqrt(r2)) / kMicro;
  // The reads' covariance from the same sums: N's top-left block is 4 sum m m^T, its last
  // column 2 sum m.
  const Eigen::Vector3d mean = normal_.block<3, 1>(0, 3) / (2.0 * n);
  const Eigen::Matrix3d spread =
      normal_.topLeftCorner<3, 3>() / (4.0 * n) - mean * mean.transpose();
  const double least = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues()(0);
  s.least_spread = std::sqrt(std::max(0.0, least)) / kMicro;
  s.reads = n_;
  return s;
}

}  // namespace attitude_propagator
