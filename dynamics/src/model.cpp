#include "csp/dynamics/model.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>

namespace csp {

const LinkWrenches kNoLinkWrenches = [] {
  LinkWrenches none;
  for (auto& wrench : none) wrench.setZero();
  return none;
}();

namespace {
JointGeometry joint_geometry(const MdhParameters& row) {
  const double ca = std::cos(row.alpha), sa = std::sin(row.alpha);
  return {ca, sa, row.theta_offset, Vector3(row.a, -sa * row.d, ca * row.d)};
}

void check_flange_body(const RigidBodyInertia& body, const char* what) {
  if (!std::isfinite(body.mass) || body.mass < 0.0 || !body.com.allFinite() || !body.inertia.allFinite())
    throw std::invalid_argument(std::string(what) + ": mass must be finite and >= 0, CoM and inertia finite");
  if (!body.inertia.isApprox(body.inertia.transpose(), 1e-12))
    throw std::invalid_argument(std::string(what) + ": inertia must be symmetric");
}

}  // namespace

Transform mdh_transform(const MdhParameters& row, double q) {
  const double theta = q + row.theta_offset;
  return joint_geometry(row).transform(std::cos(theta), std::sin(theta));
}

RigidBodyInertia combine(const RigidBodyInertia& a, const RigidBodyInertia& b) {
  const double mass = a.mass + b.mass;
  if (mass <= 0.0) return {};
  const Vector3 com = (a.mass * a.com + b.mass * b.com) / mass;
  // Parallel-axis theorem: I_C = I_Ci - m_i [r_i]x^2 with r_i the offset of body i from the joint CoM.
  const Matrix3 ra = skew(a.com - com), rb = skew(b.com - com);
  return {mass, com, a.inertia - a.mass * ra * ra + b.inertia - b.mass * rb * rb};
}

Model::Model(const ModelParameters& parameters) : parameters_(parameters) {
  check_flange_body(parameters_.end_effector, "end effector");
  check_flange_body(parameters_.load, "load");
  if (!parameters_.gravity.allFinite()) throw std::invalid_argument("gravity must be finite");
  if (!parameters_.armature.allFinite() || (parameters_.armature.array() < 0.0).any())
    throw std::invalid_argument("armature: expected 7 finite non-negative rotor inertias [kg m^2]");
  total_flange_load_ = combine(parameters_.end_effector, parameters_.load);
  for (int i = 0; i < kNumJoints; ++i) {
    joints_[i] = joint_geometry(parameters_.joints[i]);
    bodies_[i] = SpatialInertia::from(parameters_.links[i]);
  }
  // Lump end effector and load on link 7, like libfranka's model does.
  bodies_[kNumJoints - 1] += SpatialInertia::from(total_flange_load_).expressed_in(parameters_.link7_T_flange);
}

Model with_load(const Model& model, const RigidBodyInertia& load) {
  ModelParameters p = model.parameters();
  p.load = load;
  return Model(p);
}

Model with_gravity(const Model& model, const Vector3& gravity) {
  ModelParameters p = model.parameters();
  p.gravity = gravity;
  return Model(p);
}

bool is_physical_inertia(const Matrix3& I) {
  if (!I.isApprox(I.transpose(), 1e-12)) return false;
  const Vector3 moments = Eigen::SelfAdjointEigenSolver<Matrix3>(I, Eigen::EigenvaluesOnly).eigenvalues();
  if (moments.minCoeff() <= 0.0) return false;
  const double sum = moments.sum();
  for (int k = 0; k < 3; ++k)
    if (moments[k] > sum - moments[k] + 1e-12 * sum) return false;
  return true;
}

}  // namespace csp
