#include "csp/gap/part.hpp"

#include <Eigen/QR>
#include <random>

#include "csp/dynamics/algorithms.hpp"

namespace csp::gap {

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

Part evaluate_part(const Model& model, const InertialRegressor& regressor, Samples samples) {
  Part part;
  const std::size_t n = samples.size();
  const Eigen::Index rows = kNumJoints * static_cast<Eigen::Index>(n);
  part.inertial.resize(rows, kInertialParameters);
  part.tilt.resize(rows, 2);
  // Gravity is linear in the gravity vector: a small tilt by angle a about base axis e turns g
  // into g + a e x g, adding the gravity torque of the vector e x g.
  const Model tilt_x = with_gravity(model, Vector3::UnitX().cross(model.gravity()));
  const Model tilt_y = with_gravity(model, Vector3::UnitY().cross(model.gravity()));
  Data data;
  for (std::size_t k = 0; k < n; ++k) {
    Vector7 tau, g, gx, gy;
    rnea(model, data, samples.q[k], samples.dq[k], samples.ddq[k], tau);
    part.predicted.push_back(tau + friction_torque(model.parameters().friction, samples.dq[k]));
    gravity_torque(model, data, samples.q[k], g);
    part.gravity.push_back(g);
    gravity_torque(tilt_x, data, samples.q[k], gx);
    gravity_torque(tilt_y, data, samples.q[k], gy);
    const Eigen::Index row = kNumJoints * static_cast<Eigen::Index>(k);
    part.tilt.block<kNumJoints, 1>(row, 0) = gx;
    part.tilt.block<kNumJoints, 1>(row, 1) = gy;
    part.inertial.middleRows<kNumJoints>(row) = regressor(data, samples.q[k], samples.dq[k], samples.ddq[k]);
  }
  part.residual = stack(samples.tau) - stack(part.predicted);
  part.samples = std::move(samples);
  return part;
}

Eigen::VectorXd stack(const std::vector<Vector7>& series) {
  Eigen::VectorXd out(kNumJoints * static_cast<Eigen::Index>(series.size()));
  for (std::size_t k = 0; k < series.size(); ++k)
    out.segment<kNumJoints>(kNumJoints * static_cast<Eigen::Index>(k)) = series[k];
  return out;
}

Vector7 joint_mean_square(const Eigen::VectorXd& stacked) {
  const Eigen::Map<const Eigen::Matrix<double, kNumJoints, Eigen::Dynamic>> m(stacked.data(), kNumJoints,
                                                                              stacked.size() / kNumJoints);
  return m.rowwise().squaredNorm() / static_cast<double>(m.cols());
}

}  // namespace csp::gap
