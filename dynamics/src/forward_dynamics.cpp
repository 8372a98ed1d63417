#include "steps.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp {
namespace {

// aba's own 6-vector steps. They build each 6-vector from six scalars: spatial.hpp's
// `v << linear, angular` stores two 3-vectors that the 6-wide loads of the next step read back at
// once, which stalls store forwarding (perf: about a tenth of aba's samples). They are not the
// shared forms because there the same change slows FK and changes the Coriolis matrix's last bits.
Vector6 stacked(const Vector3& linear, const Vector3& angular) {
  return Vector6(linear.x(), linear.y(), linear.z(), angular.x(), angular.y(), angular.z());
}
Vector6 momentum(const SpatialInertia& I, const Vector6& v) {
  const Vector3 u = v.head<3>(), w = v.tail<3>();
  return stacked(I.mass * u - I.first_moment.cross(w), I.rotational * w + I.first_moment.cross(u));
}
Vector6 motion_cross_motion(const Vector6& v, const Vector6& m) {   // v x m
  const Vector3 u = v.head<3>(), w = v.tail<3>();
  return stacked(w.cross(m.head<3>()) + u.cross(m.tail<3>()), w.cross(m.tail<3>()));
}
Vector6 motion_cross_force(const Vector6& v, const Vector6& f) {   // v x* f
  const Vector3 u = v.head<3>(), w = v.tail<3>();
  return stacked(w.cross(f.head<3>()), u.cross(f.head<3>()) + w.cross(f.tail<3>()));
}

// I_A += I.matrix() without forming the 6x6 matrix, whose block-by-block stores pass 2 read back at
// once (perf: a tenth of aba's samples stalled on that load). [h]x below, -[h]x to its right.
void add_inertia(Matrix6& I_A, const SpatialInertia& I) {
  const Vector3& h = I.first_moment;
  for (int k = 0; k < 3; ++k) I_A(k, k) += I.mass;
  I_A(4, 0) += h.z(), I_A(5, 0) -= h.y(), I_A(3, 1) -= h.z(), I_A(5, 1) += h.x(), I_A(3, 2) += h.y(), I_A(4, 2) -= h.x();
  I_A(1, 3) -= h.z(), I_A(2, 3) += h.y(), I_A(0, 4) += h.z(), I_A(2, 4) -= h.x(), I_A(0, 5) -= h.y(), I_A(1, 5) += h.x();
  I_A.bottomRightCorner<3, 3>() += I.rotational;
}

// Articulated-body algorithm in base coordinates (Featherstone Table 7.1 with all quantities in
// the base frame, so no inertia is ever transformed between links). f_ext may be null: no wrenches.
void articulated_body(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau,
                      const LinkWrenches* f_ext) {
  detail::update_joint_frames(model, data, q);   // the flange, EE and K frames are not needed
  detail::update_base_inertias(model, data);
  detail::update_base_velocities<motion_cross_motion>(data, dq);

  // Pass 1: velocity-product forces v x* I v, less the external wrenches.
  std::array<Vector6, kNumJoints> p;
  for (int i = 0; i < kNumJoints; ++i) {
    const Vector6& v = data.velocity[i];
    p[i] = motion_cross_force(v, momentum(data.O_inertia[i], v));
    if (f_ext) p[i] -= detail::wrench_in_base(data.O_T_joint[i], (*f_ext)[i]);
  }

  // Pass 2 (tip to base) carries one articulated inertia I^A and bias force p^A. The chain
  // U -> D -> 1/D -> I^A of the parent -> its U is the critical path, so the parent's U is formed
  // as (I^A + I_parent) S_parent - U (U.S_parent) / D: the 6x6 product does not wait for 1/D.
  Matrix6 I_A = data.O_inertia[kNumJoints - 1].matrix();
  Vector6 p_A = p[kNumJoints - 1];
  Vector6 U = I_A * data.axis[kNumJoints - 1];
  std::array<double, kNumJoints> D_inverse, U_dot_S_parent{};
  for (int i = kNumJoints - 1; i >= 0; --i) {
    const Vector6& S = data.axis[i];
    data.U[i] = U;
    data.D[i] = model.armature()[i] + S.dot(U);   // the rotor's inertia adds to D (RBDA sec. 7.3)
    data.u[i] = tau[i] - S.dot(p_A);
    D_inverse[i] = 1.0 / data.D[i];
    if (i > 0) {
      // Handed to the parent: I^a = I^A - U U^T / D and p^a = p^A + I^a c + U u / D, written as
      // p^A + I^A c + U (u - U.c) / D (one 6x6 product with c instead of two).
      const Vector6& c = data.bias_acceleration[i];
      const Vector6& S_parent = data.axis[i - 1];
      p_A += I_A * c + U * ((data.u[i] - U.dot(c)) * D_inverse[i]) + p[i - 1];
      add_inertia(I_A, data.O_inertia[i - 1]);
      const Vector6 W = I_A * S_parent;
      I_A.noalias() -= (U * D_inverse[i]) * U.transpose();
      U_dot_S_parent[i] = U.dot(S_parent);
      U = W - U * (U_dot_S_parent[i] * D_inverse[i]);
    }
  }

  // Pass 3 (base to tip): ddq_i = (u_i - U_i . a_i') / D_i with a_i' = a_parent + c_i. The parent's
  // own joint term enters by the scalar U_i . S_parent from pass 2, so each ddq waits one multiply-add
  // for the last, not a 6-vector update and a dot product. a is a_parent less S_parent ddq_parent.
  // The base accelerates upwards against gravity.
  Vector6 a = linear_angular(-model.gravity(), Vector3::Zero());
  double ddq_parent = 0.0;
  for (int i = 0; i < kNumJoints; ++i) {
    a += data.bias_acceleration[i];
    data.ddq[i] = (data.u[i] - data.U[i].dot(a) - U_dot_S_parent[i] * ddq_parent) * D_inverse[i];
    if (i > 0) a += data.axis[i - 1] * ddq_parent;
    ddq_parent = data.ddq[i];
  }
}

// Solves M x = b for a symmetric positive definite M by M = L D L^T, L unit lower triangular
// (Golub & Van Loan, alg. 4.1.2), written for the fixed 7x7: no square roots, and the only
// divisions are the 7 reciprocals of D, which form the critical path of the factorisation.
Vector7 solve_ldlt(const Matrix7& M, const Vector7& b) {
  Matrix7 L, LD;   // strictly lower parts: L and L D
  Vector7 D_inverse;
  for (int j = 0; j < kNumJoints; ++j) {
    double D = M(j, j);
    for (int k = 0; k < j; ++k) D -= L(j, k) * LD(j, k);
    D_inverse[j] = 1.0 / D;
    for (int i = j + 1; i < kNumJoints; ++i) {
      double x = M(i, j);
      for (int k = 0; k < j; ++k) x -= L(i, k) * LD(j, k);
      LD(i, j) = x;
      L(i, j) = x * D_inverse[j];
    }
  }
  Vector7 x = b;
  for (int i = 1; i < kNumJoints; ++i)   // L y = b
    for (int k = 0; k < i; ++k) x[i] -= L(i, k) * x[k];
  x = x.cwiseProduct(D_inverse);
  for (int i = kNumJoints - 2; i >= 0; --i)   // L^T x = D^-1 y
    for (int k = i + 1; k < kNumJoints; ++k) x[i] -= L(k, i) * x[k];
  return x;
}

}  // namespace

void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau,
         const LinkWrenches& f_ext) {
  articulated_body(model, data, q, dq, tau, &f_ext);
}

void aba(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& tau) {
  articulated_body(model, data, q, dq, tau, nullptr);
}

// M ddq = tau - b with the bias b = c + g - sum J^T f_ext: the inverse dynamics at ddq = 0.
void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau, const LinkWrenches& f_ext) {
  Vector7 bias;
  rnea(model, data, q, dq, Vector7::Zero(), f_ext, bias);
  detail::composite_rigid_body(model, data);   // rnea left the sines and cosines of q in data
  data.ddq = solve_ldlt(data.mass_matrix, tau - bias);
}

void forward_dynamics_cholesky(const Model& model, Data& data, const Vector7& q, const Vector7& dq,
                               const Vector7& tau) {
  forward_dynamics_cholesky(model, data, q, dq, tau, kNoLinkWrenches);
}

}  // namespace csp
