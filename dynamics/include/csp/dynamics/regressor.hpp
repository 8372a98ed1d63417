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

// tau = Y(q, dq, ddq) pi. Column k is the RNEA torque of the model with standard parameter k
// increased by one minus that of the model itself: exact because the torque is linear in pi.
class InertialRegressor {
 public:
  explicit InertialRegressor(const Model& model);
  InertialRegressorRows operator()(Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq) const;

 private:
  Model nominal_;
  std::vector<Model> perturbed_;  // kInertialParameters models
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
