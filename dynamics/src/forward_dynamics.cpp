#include "steps.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp {
// Articulated-body algorithm in base coordinates (Featherstone Table 7.1 with all quantities in
// the base frame, so no inertia is ever transformed between links).
void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau,
         const LinkWrenches& f_ext) {
  detail::update_joint_frames(model, data, q);   // the flange, EE and K frames are not needed
  detail::update_base_inertias(model, data);
  detail::update_base_velocities(data, dq);

  // Pass 1: rigid-body inertias and velocity-product forces.
  for (int i = 0; i < kNumJoints; ++i) {
    const SpatialInertia& I = data.O_inertia[i];
    const Vector6& v = data.velocity[i];
    data.articulated[i] = I.matrix();
    data.bias_force[i] = cross_force(v, I * v) - detail::wrench_in_base(data.O_T_joint[i], f_ext[i]);
  }

  // Pass 2 (tip to base): articulated inertias and bias forces.
  for (int i = kNumJoints - 1; i >= 0; --i) {
    const Vector6& S = data.axis[i];
    data.U[i] = data.articulated[i] * S;
    data.D[i] = model.armature()[i] + S.dot(data.U[i]);   // the rotor's inertia adds to D (RBDA sec. 7.3)
    data.u[i] = tau[i] - S.dot(data.bias_force[i]);
    if (i > 0) {
      // I^a = I^A - U U^T / D and p^a = p^A + I^a c + U u / D, handed to the parent.
      const Vector6& U = data.U[i];
      const Vector6& c = data.bias_acceleration[i];
      data.articulated[i - 1] += data.articulated[i];
      data.articulated[i - 1].noalias() -= (U / data.D[i]) * U.transpose();
      data.bias_force[i - 1] += data.bias_force[i] + data.articulated[i] * c + U * ((data.u[i] - U.dot(c)) / data.D[i]);
    }
  }

  // Pass 3 (base to tip): accelerations. The base accelerates upwards against gravity.
  Vector6 a = linear_angular(-model.gravity(), Vector3::Zero());
  for (int i = 0; i < kNumJoints; ++i) {
    a += data.bias_acceleration[i];
    data.ddq[i] = (data.u[i] - data.U[i].dot(a)) / data.D[i];
    a += data.axis[i] * data.ddq[i];
  }
}

void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau) {
  aba(model, data, q, dq, tau, kNoLinkWrenches);
}

// M ddq = tau - b with the bias b = c + g - sum J^T f_ext: the inverse dynamics at ddq = 0.
void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau, const LinkWrenches& f_ext) {
  crba(model, data, q);
  Vector7 bias;
  rnea(model, data, q, dq, Vector7::Zero(), f_ext, bias);
  data.mass_cholesky.compute(data.mass_matrix);
  data.ddq = data.mass_cholesky.solve(tau - bias);
}

void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau) {
  forward_dynamics_cholesky(model, data, q, dq, tau, kNoLinkWrenches);
}

}  // namespace csp
