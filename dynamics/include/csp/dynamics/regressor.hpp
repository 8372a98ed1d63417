// The inertial regressor: joint torques are linear in the 70 standard inertial parameters
// (Atkeson, An & Hollerbach, IJRR 1986), tau = Y(q, dq, ddq) pi, and only base combinations of them
// are identifiable (Gautier & Khalil, IEEE TRA 1990). Shared by the gap diagnosis (gap/) and the
// excitation design (planners/).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"

namespace csp {

constexpr int kLinkParameters = 10;                                // m, h (3), I_O (6) per link
constexpr int kInertialParameters = kNumJoints * kLinkParameters;  // 70

using LinkParameters = Eigen::Matrix<double, kLinkParameters, 1>;
using InertialRegressorRows = Eigen::Matrix<double, kNumJoints, kInertialParameters>;

// (m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz): mass, first moment and rotational inertia about the
// link-frame origin. The joint torques are linear in these 70 numbers (the standard parameters).
LinkParameters link_parameters(const SpatialInertia& body);
SpatialInertia spatial_inertia(const LinkParameters& p);
// Mass, CoM and inertia about the CoM; mass must be > 0.
RigidBodyInertia rigid_body(const SpatialInertia& body);

// Physical consistency (Wensing, Kim and Slotine 2017): the parameters are those of some body with a
// nonnegative density exactly when the pseudo-inertia J = [Sigma h; h^T m] is positive definite, where
// Sigma = tr(I_O) / 2 1 - I_O is the second moment of the mass about the link origin (the sum over
// the body of x x^T dm). Stronger than positive mass and inertia: it implies the triangle inequality.
Eigen::Matrix4d pseudo_inertia(const LinkParameters& p);
bool physically_consistent(const LinkParameters& p);

// The log-Cholesky parametrisation (Rucker and Wensing 2022): J = U U^T with
//   U = e^alpha [e^d1 s12 s13 t1; 0 e^d2 s23 t2; 0 0 e^d3 t3; 0 0 0 1],
// theta = (alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3). Every theta is a physically consistent
// body and every such body has exactly one theta: a fit over theta is unconstrained yet physical.
LinkParameters from_log_cholesky(const LinkParameters& theta);
// d from_log_cholesky / d theta (10 x 10), exact.
Eigen::Matrix<double, kLinkParameters, kLinkParameters> from_log_cholesky_jacobian(const LinkParameters& theta);
// Throws std::domain_error when p is not physically consistent.
LinkParameters to_log_cholesky(const LinkParameters& p);

// tau = Y(q, dq, ddq) pi (the armature's I_a ddq aside): the Newton-Euler recursion of rnea with
// each link's wrench written as its 6x10 regressor, carried inward column by column. Column k is
// the torque that standard parameter k contributes per unit, what rnea of the model with that
// parameter increased by one gives minus rnea of the model itself (tests/test_dynamics_fast.cpp).
class InertialRegressor {
 public:
  explicit InertialRegressor(const Model& model);
  InertialRegressorRows operator()(Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq) const;

 private:
  Model model_;   // kinematics and gravity; its inertias are not read
};

// Identifiable combinations of the standard parameters: the independent columns of the regressor
// over random states (column-pivoted QR), in pivot order.
struct BaseParameters {
  std::vector<int> columns;
  Eigen::MatrixXd random_regressor;  // the regressor of the random states (7 S x 70)
  std::vector<Vector7> random_q;     // the random states' positions (for consistency checks)
};
BaseParameters base_parameters(const Model& model, unsigned seed = 1, int states = 200);

}  // namespace csp
