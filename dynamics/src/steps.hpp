// Steps shared by the algorithms. Internal header.
#pragma once

#include <cstddef>

#include "csp/dynamics/model.hpp"

namespace csp::detail {

// sin and cos of seven angles at once (vectorised, src/joint_trig.cpp).
void joint_sin_cos(const Vector7& theta, Vector7& sin_theta, Vector7& cos_theta);
// sin and cos of n angles, n a multiple of 4 (four per libmvec call; batch.cpp's blocks of states).
void sin_cos_in_fours(const double* theta, double* sin_theta, double* cos_theta, std::ptrdiff_t n);

// data.cos_theta, data.sin_theta of theta_i = q_i + theta_offset_i.
inline void update_joint_angles(const Model& model, Data& data, const Vector7& q) {
  Vector7 theta;
  for (int i = 0; i < kNumJoints; ++i) theta[i] = q[i] + model.joint(i).theta_offset;
  joint_sin_cos(theta, data.sin_theta, data.cos_theta);
}

// crba at the angles already in data.cos_theta, data.sin_theta (src/crba.cpp).
void composite_rigid_body(const Model& model, Data& data);

// The joint part of forward_kinematics: data.O_T_joint and data.axis (src/kinematics.cpp).
void update_joint_frames(const Model& model, Data& data, const Vector7& q);

// After update_joint_frames: every body's spatial inertia in the base frame.
inline void update_base_inertias(const Model& model, Data& data) {
  for (int i = 0; i < kNumJoints; ++i) data.O_inertia[i] = model.body(i).expressed_in(data.O_T_joint[i]);
}

// After update_joint_frames: body velocities v_i = v_{i-1} + S_i dq_i and the velocity-product
// accelerations c_i = v_i x S_i dq_i (in base coordinates dS_i/dt = v_i x S_i, Featherstone sec. 2.12).
// `cross` is the motion cross product v x m (aba passes its own form, src/forward_dynamics.cpp).
template <Vector6 (*cross)(const Vector6&, const Vector6&) = cross_motion>
inline void update_base_velocities(Data& data, const Vector7& dq) {
  Vector6 v = Vector6::Zero();
  for (int i = 0; i < kNumJoints; ++i) {
    const Vector6 joint_velocity = data.axis[i] * dq[i];
    v += joint_velocity;
    data.velocity[i] = v;
    data.bias_acceleration[i] = cross(v, joint_velocity);
  }
}

// A wrench given in link frame i (force; moment about the link origin) expressed in the base frame.
inline Vector6 wrench_in_base(const Transform& O_T_link, const Vector6& wrench) {
  const Vector3 force = O_T_link.rotation * wrench.head<3>();
  return linear_angular(force, O_T_link.rotation * wrench.tail<3>() + O_T_link.translation.cross(force));
}

}  // namespace csp::detail
