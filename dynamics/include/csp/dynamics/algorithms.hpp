// The dynamics algorithms. Each writes into Data and allocates nothing.
#pragma once

#include "csp/dynamics/model.hpp"

namespace csp {

// Pose of every joint frame, the flange, EE and K frames, and the joint axes S_i.
void forward_kinematics(const Model& model, Data& data, const Vector7& q);

// After forward_kinematics:
const Transform& frame_pose(const Data& data, Frame frame);
// Geometric Jacobian of `frame` in the base frame (seed paper eqs. 2-3; libfranka zeroJacobian):
// rows linear velocity of the frame origin, then angular velocity.
void zero_jacobian(const Data& data, Frame frame, Matrix6x7& jacobian);
// Linear Jacobian (base frame) of a point `point` (base frame) carried by link `link` (1..7; the
// flange, the tool and its contacts ride on link 7): column j < link is joint j's axis acting on the
// point, u_j + w_j x point; columns of the joints beyond the link are zero. The linear rows of
// zero_jacobian for a point that is no frame: contact points, the trocar's shaft crossing.
Matrix3x7 point_jacobian(const Data& data, int link, const Vector3& point);
// The same Jacobian with both rows expressed in `frame` (libfranka bodyJacobian).
void body_jacobian(const Data& data, Frame frame, Matrix6x7& jacobian);
// Time derivative of zero_jacobian along joint velocity dq.
void zero_jacobian_time_derivative(const Data& data, Frame frame, const Vector7& dq, Matrix6x7& jacobian_dot);

// Recursive Newton-Euler (Craig eqs. 6.45-6.53; the seed paper's eqs. 5-9):
// tau = (M(q) + diag(armature)) ddq + C(q,dq) dq + g(q) - sum_i J_i^T f_ext_i, with the model's gravity.
void rnea(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq, Vector7& tau);
void rnea(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq,
          const LinkWrenches& f_ext, Vector7& tau);
// g(q): the torques that hold the arm still against gravity.
void gravity_torque(const Model& model, Data& data, const Vector7& q, Vector7& g);
// C(q,dq) dq (no gravity).
void coriolis_torque(const Model& model, Data& data, const Vector7& q, const Vector7& dq, Vector7& c);

// Mass matrix by the composite-rigid-body algorithm (Featherstone Table 6.2), plus the armature on
// the diagonal -> data.mass_matrix.
void crba(const Model& model, Data& data, const Vector7& q);

// Coriolis matrix C(q,dq) with dM/dt - 2C skew-symmetric (Echeandia & Wensing 2021) -> data.coriolis_matrix.
void coriolis_matrix(const Model& model, Data& data, const Vector7& q, const Vector7& dq);

// Forward dynamics ddq = (M + diag(armature))^-1 (tau - c - g + sum J^T f_ext) -> data.ddq.
// Articulated-body algorithm (Featherstone Table 7.1, in base coordinates):
void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau);
void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau,
         const LinkWrenches& f_ext);
// The same through the Cholesky factor of M (crba + rnea bias): cross-checks aba, and is the
// emulator's plant step.
void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau);
void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau, const LinkWrenches& f_ext);

}  // namespace csp
