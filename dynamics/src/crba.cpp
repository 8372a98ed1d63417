#include "csp/dynamics/algorithms.hpp"
#include "steps.hpp"

namespace csp {
namespace {

// The z component of ^{i-1}R_i n + p x ^{i-1}R_i f (a wrench moved to the parent frame, RotZ(theta)
// then RotX(alpha)), without the other five: 11 multiplications instead of 22.
double z_moment_in_parent(const JointGeometry& joint, double c, double s, const Vector3& force,
                          const Vector3& moment) {
  const double force_x = c * force.x() - s * force.y();
  const double force_y = joint.cos_alpha * (s * force.x() + c * force.y()) - joint.sin_alpha * force.z();
  const double rotated_moment_z = joint.sin_alpha * (s * moment.x() + c * moment.y()) + joint.cos_alpha * moment.z();
  return rotated_moment_z + (joint.origin.x() * force_y - joint.origin.y() * force_x);
}

// The zz entry of I's rotational inertia expressed in the parent frame about its origin
// (JointGeometry::rotate_symmetric, then SpatialInertia::shifted), without the other entries.
double zz_in_parent(const JointGeometry& joint, double c, double s, const SpatialInertia& I) {
  const Matrix3& R = I.rotational;
  // RotZ(theta) keeps zz and moves yy and yz; RotX(alpha) then mixes y and z.
  const double yy = s * s * R(0, 0) + 2.0 * c * s * R(0, 1) + c * c * R(1, 1);
  const double yz = s * R(0, 2) + c * R(1, 2);
  const double ca = joint.cos_alpha, sa = joint.sin_alpha;
  const double zz = sa * sa * yy + 2.0 * ca * sa * yz + ca * ca * R(2, 2);
  // The parallel axis, (2 h.p + m p.p) - p_z g_z - h_z p_z with g = h + m p, as in shifted().
  const Vector3 h = joint.rotate(c, s, I.first_moment);
  const Vector3& p = joint.origin;
  return zz + 2.0 * h.dot(p) + I.mass * p.squaredNorm() - p.z() * (h.z() + I.mass * p.z()) - h.z() * p.z();
}

}  // namespace

// Composite-rigid-body algorithm in link coordinates (Featherstone Table 6.2). The composite
// inertia of bodies i..7 is accumulated from the tip; F = I^c_i S_i is carried down the chain as
// a force, and M_ji = S_j . F in each ancestor's frame. Every S_j is the link's z axis, so
// S_j . F is the moment's z component and I^c_i S_i is read off the inertia directly.
void detail::composite_rigid_body(const Model& model, Data& data) {
  SpatialInertia composite = model.body(kNumJoints - 1);
  for (int i = kNumJoints - 1; i > 0; --i) {
    // F = I^c (0; e_z) = (-h x e_z; I_O e_z). The composite inertia's chain is the critical path:
    // it moves on before this column is carried down.
    Vector3 force(-composite.first_moment.y(), composite.first_moment.x(), 0.0);
    Vector3 moment = composite.rotational.col(2);
    data.mass_matrix(i, i) = moment.z();
    if (i > 1) {   // I^c_{i-1} = I_{i-1} + (I^c_i expressed in frame i-1)
      const JointGeometry& joint = model.joint(i);
      const double c = data.cos_theta[i], s = data.sin_theta[i];
      composite = SpatialInertia{composite.mass, joint.rotate(c, s, composite.first_moment),
                                 joint.rotate_symmetric(c, s, composite.rotational)}
                      .shifted(joint.origin);
      composite += model.body(i - 1);
    }
    for (int j = i; j > 1; --j) {   // force transform from frame j to frame j-1
      const JointGeometry& joint = model.joint(j);
      const double c = data.cos_theta[j], s = data.sin_theta[j];
      force = joint.rotate(c, s, force);
      moment = joint.rotate(c, s, moment) + joint.origin.cross(force);
      data.mass_matrix(j - 1, i) = data.mass_matrix(i, j - 1) = moment.z();
    }
    // Into frame 0, where nothing is carried further: only the z moment.
    data.mass_matrix(0, i) = data.mass_matrix(i, 0) =
        z_moment_in_parent(model.joint(1), data.cos_theta[1], data.sin_theta[1], force, moment);
  }
  // Joint 1's column is M_11 alone, the zz entry of I^c_0 = I_0 + (I^c_1 expressed in frame 0).
  data.mass_matrix(0, 0) =
      model.body(0).rotational(2, 2) + zz_in_parent(model.joint(1), data.cos_theta[1], data.sin_theta[1], composite);
  // The rotors add their reflected inertia on the diagonal: M + diag(I_a) (Featherstone sec. 7.3).
  data.mass_matrix.diagonal() += model.armature();
}

void crba(const Model& model, Data& data, const Vector7& q) {
  detail::update_joint_angles(model, data, q);
  detail::composite_rigid_body(model, data);
}

}  // namespace csp
