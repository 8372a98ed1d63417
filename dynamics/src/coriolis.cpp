#include "steps.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp {

// Coriolis matrix by Echeandia & Wensing, "A Numerical Method for Computing the Coriolis Matrix
// and Christoffel Symbols for Rigid-Body Systems" (2021), in base coordinates:
//   C = sum_i J_i^T (I_i dJ_i + B_i J_i),  B_i = 1/2 [ (v_i x*) I_i + (I_i v_i) x-bar* - I_i (v_i x) ],
// so that B_i + B_i^T = dI_i/dt and hence dM/dt - 2C is skew-symmetric. Columns of J_i are the axes
// S_k (k <= i) and those of dJ_i are dS_k/dt = v_k x S_k; summing from the tip gives O(n^2).
// The armature is a constant diagonal inertia: it adds nothing to C.
void coriolis_matrix(const Model& model, Data& data, const Vector7& q, const Vector7& dq) {
  forward_kinematics(model, data, q);
  detail::update_base_inertias(model, data);
  detail::update_base_velocities(data, dq);

  std::array<Vector6, kNumJoints> axis_dot;
  for (int k = 0; k < kNumJoints; ++k) axis_dot[k] = cross_motion(data.velocity[k], data.axis[k]);

  Matrix6 composite_inertia = Matrix6::Zero(), composite_B = Matrix6::Zero();
  for (int m = kNumJoints - 1; m >= 0; --m) {
    const Matrix6 I = data.O_inertia[m].matrix();
    const Vector6& v = data.velocity[m];
    composite_inertia += I;
    composite_B += 0.5 * (cross_force_matrix(v) * I + cross_force_bar_matrix(I * v) - I * cross_motion_matrix(v));

    // Entries whose larger index is m: C(j, m) for j <= m and C(m, k) for k < m.
    const Vector6 F = composite_inertia * axis_dot[m] + composite_B * data.axis[m];
    for (int j = 0; j <= m; ++j) data.coriolis_matrix(j, m) = data.axis[j].dot(F);
    const Vector6 a = composite_inertia * data.axis[m];
    const Vector6 b = composite_B.transpose() * data.axis[m];
    for (int k = 0; k < m; ++k) data.coriolis_matrix(m, k) = a.dot(axis_dot[k]) + b.dot(data.axis[k]);
  }
}

}  // namespace csp
