#include "csp/dynamics/regressor.hpp"

#include <Eigen/QR>
#include <random>

#include "csp/dynamics/algorithms.hpp"

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

namespace {

// The model with the load lumped into link 7 and link `link`'s standard parameters moved by delta.
Model with_link_parameters(const Model& model, int link, const LinkParameters& delta) {
  ModelParameters p = model.parameters();
  p.end_effector = p.load = RigidBodyInertia{};
  for (int i = 0; i < kNumJoints; ++i) {
    const LinkParameters value = link_parameters(model.body(i)) + (i == link ? delta : LinkParameters::Zero());
    p.links[i] = rigid_body(spatial_inertia(value));
  }
  return Model(p);
}

}  // namespace

InertialRegressor::InertialRegressor(const Model& model) : nominal_(model) {
  perturbed_.reserve(kInertialParameters);
  for (int k = 0; k < kInertialParameters; ++k)
    perturbed_.push_back(with_link_parameters(model, k / kLinkParameters, LinkParameters::Unit(k % kLinkParameters)));
}

InertialRegressorRows InertialRegressor::operator()(Data& data, const Vector7& q, const Vector7& dq,
                                                    const Vector7& ddq) const {
  Vector7 tau0, tau;
  rnea(nominal_, data, q, dq, ddq, tau0);
  InertialRegressorRows Y;
  for (int k = 0; k < kInertialParameters; ++k) {
    rnea(perturbed_[k], data, q, dq, ddq, tau);
    Y.col(k) = tau - tau0;
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
