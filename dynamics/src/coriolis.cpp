#include "steps.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp {
namespace {

// B_i of Echeandia & Wensing (2021) eq. 17 for one body, in base coordinates:
//   B = 1/2 [ (v x*) I + (I v) x-bar* - I (v x) ],  v = (u; w), I v = (f; n), I = [m 1, -[h]x; [h]x, I_O].
// Multiplied out block by block (linear first), the left column vanishes and
//   B = [ 0, -[f]x ; 0, D ],  D = sym([w]x I_O - h u^T) + (u.h) 1 - [n]x / 2,
// with sym(X) = (X + X^T)/2 ([w]x I_O - I_O [w]x and -[u]x[h]x - [h]x[u]x are the symmetric parts
// of twice those products). B is thus a 3-vector f and a 3x3 D instead of a 6x6 matrix: the
// composite sums over the subtree cost 12 additions, and B S, B^T S a cross and a 3x3 product.
struct CoriolisFactor {
  Vector3 f = Vector3::Zero();
  Matrix3 D = Matrix3::Zero();

  static CoriolisFactor of(const SpatialInertia& I, const Vector6& v) {
    const Vector3 u = v.head<3>(), w = v.tail<3>();
    const Vector6 momentum = I * v;
    const Vector3 n = momentum.tail<3>();
    Matrix3 K;
    for (int c = 0; c < 3; ++c) K.col(c) = w.cross(I.rotational.col(c)) - I.first_moment * u[c];
    Matrix3 D = 0.5 * (K + K.transpose()) - 0.5 * skew(n);
    D.diagonal().array() += u.dot(I.first_moment);
    return {momentum.head<3>(), D};
  }

  CoriolisFactor& operator+=(const CoriolisFactor& other) {
    f += other.f;
    D += other.D;
    return *this;
  }

  // B s and B^T s for a motion vector s = (a; b).
  Vector6 times(const Vector6& s) const { return linear_angular(-f.cross(s.tail<3>()), D * s.tail<3>()); }
  Vector3 transpose_times_angular(const Vector6& s) const {   // B^T s = (0; this)
    return f.cross(s.head<3>()) + D.transpose() * s.tail<3>();
  }
};

}  // namespace

// Coriolis matrix by Echeandia & Wensing, "A Numerical Method for Computing the Coriolis Matrix
// and Christoffel Symbols for Rigid-Body Systems" (2021), Algorithm 1 in base coordinates:
//   C = sum_i J_i^T (I_i dJ_i + B_i J_i),
// so that B_i + B_i^T = dI_i/dt and hence dM/dt - 2C is skew-symmetric. Columns of J_i are the axes
// S_k (k <= i) and those of dJ_i are dS_k/dt = v_k x S_k; composite I^c and B^c summed from the tip
// give O(n^2): C(j, m) = S_j . (I^c_m dS_m + B^c_m S_m) for j <= m, and
// C(m, k) = dS_k . (I^c_m S_m) + S_k . (B^c_m^T S_m) for k < m.
// The armature is a constant diagonal inertia: it adds nothing to C.
void coriolis_matrix(const Model& model, Data& data, const Vector7& q, const Vector7& dq) {
  detail::update_joint_frames(model, data, q);   // the flange, EE and K frames are not needed
  detail::update_base_inertias(model, data);
  detail::update_base_velocities(data, dq);

  std::array<Vector6, kNumJoints> axis_dot;
  for (int k = 0; k < kNumJoints; ++k) axis_dot[k] = cross_motion(data.velocity[k], data.axis[k]);

  SpatialInertia composite_inertia;
  CoriolisFactor composite_B;
  for (int m = kNumJoints - 1; m >= 0; --m) {
    composite_inertia += data.O_inertia[m];
    composite_B += CoriolisFactor::of(data.O_inertia[m], data.velocity[m]);

    const Vector6& S = data.axis[m];
    const Vector6 F = composite_inertia * axis_dot[m] + composite_B.times(S);
    for (int j = 0; j <= m; ++j) data.coriolis_matrix(j, m) = data.axis[j].dot(F);
    const Vector6 a = composite_inertia * S;
    const Vector3 b = composite_B.transpose_times_angular(S);
    for (int k = 0; k < m; ++k)
      data.coriolis_matrix(m, k) = a.dot(axis_dot[k]) + b.dot(data.axis[k].tail<3>());
  }
}

}  // namespace csp
