#include "attitude_propagator/torque_free_motion.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "attitude_propagator/quaternion.h"

namespace attitude_propagator {

TorqueFreeMotion::TorqueFreeMotion(const RigidBody& body, const DynamicState& x0, double t0)
    : t0_(t0), q_BP_(body.q_BP()), I_P_(body.principalMoments()) {
  if (!x0.q_WB.coeffs().allFinite() || !x0.w_B.allFinite() || !std::isfinite(t0)) {
    throw std::invalid_argument("TorqueFreeMotion: the initial state must be finite");
  }
  if (!(x0.q_WB.norm() > 0.0)) {
    throw std::invalid_argument("TorqueFreeMotion: the initial orientation is a zero quaternion");
  }
  q0_WP_ = x0.q_WB.normalized() * q_BP_;
  w0_P_ = q_BP_.conjugate() * x0.w_B;
  M0_P_ = I_P_.cwiseProduct(w0_P_);
  if (body.isSphere(kRelativeSymmetry)) {
    form_ = Form::Sphere;
  } else if (body.isSymmetric(kRelativeSymmetry)) {
    form_ = Form::SymmetricTop;
    initSymmetricTop(M0_P_, body.symmetryAxis(kRelativeSymmetry));
  } else {
    form_ = Form::Triaxial;
    initTriaxial(body, M0_P_);
  }
}

const char* TorqueFreeMotion::formName() const {
  switch (form_) {
    case Form::Sphere:
      return "sphere";
    case Form::SymmetricTop:
      return "symmetric_top";
    case Form::Triaxial:
      return "triaxial";
  }
  return "unknown";
}

double TorqueFreeMotion::bodyPeriod() const {
  if (regime_ == Regime::Separatrix) return std::numeric_limits<double>::infinity();
  if (regime_ == Regime::Steady) return 0.0;
  return 4.0 * K_ / std::abs(lambda_);
}

void TorqueFreeMotion::initSymmetricTop(const Eigen::Vector3d& M_P, int axis) {
  axis_ = axis;
  const int j = (axis + 1) % 3;
  const int k = (axis + 2) % 3;
  const double I_perp = 0.5 * (I_P_[j] + I_P_[k]);
  precession_W_ = (q0_WP_ * M_P) / I_perp;
  spin_ = M_P[axis] * (1.0 / I_P_[axis] - 1.0 / I_perp);
}

void TorqueFreeMotion::initTriaxial(const RigidBody&, const Eigen::Vector3d&) {
  throw std::logic_error("TorqueFreeMotion: triaxial case not implemented yet");
}

void TorqueFreeMotion::triaxialAt(double, Eigen::Vector3d&, Eigen::Quaterniond&) const {}

DynamicState TorqueFreeMotion::evaluate(double t) const {
  const double tau = t - t0_;
  Eigen::Quaterniond q_WP = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero();
  switch (form_) {
    case Form::Sphere:
      q_WP = q0_WP_ * expMap(tau * w0_P_);
      w_P = w0_P_;
      break;
    case Form::SymmetricTop: {
      const Eigen::Vector3d spin = tau * spin_ * Eigen::Vector3d::Unit(axis_);
      q_WP = expMap(tau * precession_W_) * q0_WP_ * expMap(spin);
      const Eigen::Vector3d M_P = expMap(-spin) * M0_P_;
      w_P = M_P.cwiseQuotient(I_P_);
      break;
    }
    case Form::Triaxial: {
      Eigen::Vector3d M_F;
      Eigen::Quaterniond q_WF;
      triaxialAt(tau, M_F, q_WF);
      q_WP = q_WF * q_PF_.conjugate();
      w_P = q_PF_ * Eigen::Vector3d(M_F.cwiseQuotient(I_F_));
      break;
    }
  }
  DynamicState x;
  x.q_WB = q_WP * q_BP_.conjugate();
  x.w_B = q_BP_ * w_P;
  return x;
}

}  // namespace attitude_propagator
