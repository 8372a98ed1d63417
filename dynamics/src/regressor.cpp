#include "csp/dynamics/regressor.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <random>
#include <stdexcept>

#include "csp/dynamics/algorithms.hpp"
#include "steps.hpp"

namespace csp {

LinkParameters link_parameters(const SpatialInertia& body) {
  const Matrix3& I = body.rotational;
  LinkParameters p;
  p << body.mass, body.first_moment, I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2);
  return p;
}

SpatialInertia spatial_inertia(const LinkParameters& p) {
  Matrix3 I;
  I << p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9];
  return {p[0], p.segment<3>(1), I};
}

RigidBodyInertia rigid_body(const SpatialInertia& body) {
  const Vector3 com = body.first_moment / body.mass;
  const Matrix3 c = skew(com);
  return {body.mass, com, body.rotational + body.mass * c * c};  // I_C = I_O + m [c]x [c]x
}

Eigen::Matrix4d pseudo_inertia(const LinkParameters& p) {
  const Matrix3 I = spatial_inertia(p).rotational;
  Eigen::Matrix4d J;
  J.topLeftCorner<3, 3>() = 0.5 * I.trace() * Matrix3::Identity() - I;
  J.topRightCorner<3, 1>() = p.segment<3>(1);
  J.bottomLeftCorner<1, 3>() = p.segment<3>(1).transpose();
  J(3, 3) = p[0];
  return J;
}

bool physically_consistent(const LinkParameters& p) {
  const Eigen::LLT<Eigen::Matrix4d> cholesky(pseudo_inertia(p));
  return cholesky.info() == Eigen::Success;
}

namespace {

// The standard parameters of a pseudo-inertia (the inverse of pseudo_inertia): I_O = tr(Sigma) 1 - Sigma.
LinkParameters from_pseudo_inertia(const Eigen::Matrix4d& J) {
  const Matrix3 Sigma = J.topLeftCorner<3, 3>();
  const Matrix3 I = Sigma.trace() * Matrix3::Identity() - Sigma;
  LinkParameters p;
  p << J(3, 3), J.topRightCorner<3, 1>(), I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2);
  return p;
}

// U of the log-Cholesky parametrisation, and dU / dtheta_k.
Eigen::Matrix4d log_cholesky_factor(const LinkParameters& t) {
  Eigen::Matrix4d U;
  U << std::exp(t[1]), t[4], t[6], t[7],  //
      0.0, std::exp(t[2]), t[5], t[8],     //
      0.0, 0.0, std::exp(t[3]), t[9],      //
      0.0, 0.0, 0.0, 1.0;
  return std::exp(t[0]) * U;
}

Eigen::Matrix4d log_cholesky_factor_derivative(const LinkParameters& t, int k) {
  if (k == 0) return log_cholesky_factor(t);  // U is e^alpha times the rest
  static constexpr int kRow[] = {0, 0, 1, 2, 0, 1, 0, 0, 1, 2}, kColumn[] = {0, 0, 1, 2, 1, 2, 2, 3, 3, 3};
  Eigen::Matrix4d dU = Eigen::Matrix4d::Zero();
  dU(kRow[k], kColumn[k]) = std::exp(t[0]) * (k <= 3 ? std::exp(t[k]) : 1.0);
  return dU;
}

}  // namespace

LinkParameters from_log_cholesky(const LinkParameters& theta) {
  const Eigen::Matrix4d U = log_cholesky_factor(theta);
  return from_pseudo_inertia(U * U.transpose());
}

Eigen::Matrix<double, kLinkParameters, kLinkParameters> from_log_cholesky_jacobian(const LinkParameters& theta) {
  const Eigen::Matrix4d U = log_cholesky_factor(theta);
  Eigen::Matrix<double, kLinkParameters, kLinkParameters> jacobian;
  for (int k = 0; k < kLinkParameters; ++k) {
    const Eigen::Matrix4d dU = log_cholesky_factor_derivative(theta, k);
    jacobian.col(k) = from_pseudo_inertia(dU * U.transpose() + U * dU.transpose());  // linear in J
  }
  return jacobian;
}

LinkParameters to_log_cholesky(const LinkParameters& p) {
  // J = U U^T with U upper triangular: the Cholesky factor of J with rows and columns reversed.
  const Eigen::Matrix4d reverse = Eigen::Matrix4d::Identity().rowwise().reverse();
  const Eigen::LLT<Eigen::Matrix4d> cholesky(reverse * pseudo_inertia(p) * reverse);
  if (cholesky.info() != Eigen::Success)
    throw std::domain_error("link parameters are not physically consistent (pseudo-inertia not positive definite)");
  const Eigen::Matrix4d U = reverse * Eigen::Matrix4d(cholesky.matrixL()) * reverse;
  const double scale = U(3, 3);
  LinkParameters theta;
  theta << std::log(scale), std::log(U(0, 0) / scale), std::log(U(1, 1) / scale), std::log(U(2, 2) / scale),
      U(0, 1) / scale, U(1, 2) / scale, U(0, 2) / scale, U(0, 3) / scale, U(1, 3) / scale, U(2, 3) / scale;
  return theta;
}

namespace {

using LinkRegressor = Eigen::Matrix<double, 6, kLinkParameters>;   // (force; moment) per parameter
constexpr int kFirstInertiaColumn = 4;                               // m, h (3), then I_O (6)

// L(a) with I a = L(a) (Ixx, Ixy, Ixz, Iyy, Iyz, Izz) for a symmetric I.
Eigen::Matrix<double, 3, 6> inertia_product(const Vector3& a) {
  Eigen::Matrix<double, 3, 6> L;
  L << a.x(), a.y(), a.z(), 0.0, 0.0, 0.0,  //
      0.0, a.x(), 0.0, a.y(), a.z(), 0.0,    //
      0.0, 0.0, a.x(), 0.0, a.y(), a.z();
  return L;
}

// The net wrench of one link about its origin, linear in its standard parameters (Atkeson, An and
// Hollerbach 1986): with w, dw and dv (gravity included) of the link origin in the link frame,
//   f = m dv + ([dw]x + [w]x [w]x) h,    n = -[dv]x h + L(dw) I + [w]x L(w) I
// (the Newton-Euler equations of rnea.cpp, term by term).
LinkRegressor link_regressor(const Vector3& w, const Vector3& dw, const Vector3& dv) {
  LinkRegressor A = LinkRegressor::Zero();
  A.block<3, 1>(0, 0) = dv;
  A.block<3, 3>(0, 1) = skew(dw) + skew(w) * skew(w);
  A.block<3, 3>(3, 1) = -skew(dv);
  A.block<3, 6>(3, 4) = inertia_product(dw) + skew(w) * inertia_product(w);
  return A;
}

}  // namespace

InertialRegressor::InertialRegressor(const Model& model) : model_(model) {}

// Outward the link kinematics as in rnea (Craig eqs. 6.45-6.47); then each link's 6x10 wrench
// regressor is carried inward like a wrench (Craig eqs. 6.51-6.53), column by column, and the joint
// torque rows are its moments' z components: Y(j, link i) = e_z . (^jX*_i A_i) for j <= i.
InertialRegressorRows InertialRegressor::operator()(Data& data, const Vector7& q, const Vector7& dq,
                                                    const Vector7& ddq) const {
  detail::update_joint_angles(model_, data, q);
  const Vector3 z = Vector3::UnitZ();
  Vector3 w = Vector3::Zero(), dw = Vector3::Zero(), dv = -model_.gravity();
  InertialRegressorRows Y = InertialRegressorRows::Zero();
  for (int i = 0; i < kNumJoints; ++i) {
    const JointGeometry& joint = model_.joint(i);
    const double c = data.cos_theta[i], s = data.sin_theta[i];
    const Vector3& p = joint.origin;
    const Vector3 dv_parent_at_origin = dw.cross(p) + w.cross(w.cross(p)) + dv;
    const Vector3 w_parent = joint.rotate_back(c, s, w);
    w = w_parent + dq[i] * z;
    dw = joint.rotate_back(c, s, dw) + w_parent.cross(dq[i] * z) + ddq[i] * z;
    dv = joint.rotate_back(c, s, dv_parent_at_origin);

    LinkRegressor A = link_regressor(w, dw, dv);
    for (int j = i;; --j) {
      Y.block<1, kLinkParameters>(j, kLinkParameters * i) = A.row(5);
      if (j == 0) break;
      const JointGeometry& child = model_.joint(j);
      const double cj = data.cos_theta[j], sj = data.sin_theta[j];
      for (int k = 0; k < kFirstInertiaColumn; ++k) {
        const Vector3 force = child.rotate(cj, sj, A.block<3, 1>(0, k));
        A.block<3, 1>(3, k) = child.rotate(cj, sj, A.block<3, 1>(3, k)) + child.origin.cross(force);
        A.block<3, 1>(0, k) = force;
      }
      // The rotational inertia's columns have no force, and a pure moment moved to the parent's
      // origin stays what it was, rotated: a third of a wrench's work.
      for (int k = kFirstInertiaColumn; k < kLinkParameters; ++k)
        A.block<3, 1>(3, k) = child.rotate(cj, sj, A.block<3, 1>(3, k));
    }
  }
  return Y;
}

BaseParameters base_parameters(const Model& model, unsigned seed, int states) {
  const InertialRegressor regressor(model);
  const JointLimits& limits = model.parameters().joint_limits;
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), symmetric(-1.0, 1.0);
  BaseParameters base;
  base.random_regressor.resize(kNumJoints * states, kInertialParameters);
  Data data;
  for (int s = 0; s < states; ++s) {
    Vector7 q, dq, ddq;
    for (int j = 0; j < kNumJoints; ++j) {
      q[j] = limits.q_min[j] + unit(engine) * (limits.q_max[j] - limits.q_min[j]);
      dq[j] = 2.0 * symmetric(engine);
      ddq[j] = 5.0 * symmetric(engine);
    }
    base.random_q.push_back(q);
    base.random_regressor.middleRows<kNumJoints>(kNumJoints * s) = regressor(data, q, dq, ddq);
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(base.random_regressor);
  qr.setThreshold(1e-9);
  for (Eigen::Index k = 0; k < qr.rank(); ++k)
    base.columns.push_back(static_cast<int>(qr.colsPermutation().indices()[k]));
  return base;
}

}  // namespace csp
