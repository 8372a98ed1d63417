#include "csp/dynamics/algorithms.hpp"
#include "steps.hpp"

namespace csp {
namespace {

// Number of joints that move a frame: joint frame k moves with joints 1..k, the others with all.
int moving_joints(Frame frame) {
  const int index = static_cast<int>(frame);
  return index < kNumJoints ? index + 1 : kNumJoints;
}

}  // namespace

void detail::update_joint_frames(const Model& model, Data& data, const Vector7& q) {
  update_joint_angles(model, data, q);
  Transform O_T_i;
  for (int i = 0; i < kNumJoints; ++i) {
    O_T_i = O_T_i * model.joint(i).transform(data.cos_theta[i], data.sin_theta[i]);
    data.O_T_joint[i] = O_T_i;
    // Revolute joint about z_i through o_i: S_i = (o_i x z_i; z_i) at the base origin.
    const Vector3 z = O_T_i.rotation.col(2);
    data.axis[i] = linear_angular(O_T_i.translation.cross(z), z);
  }
}

void forward_kinematics(const Model& model, Data& data, const Vector7& q) {
  detail::update_joint_frames(model, data, q);
  const ModelParameters& p = model.parameters();
  data.O_T_F = data.O_T_joint[kNumJoints - 1] * p.link7_T_flange;
  data.O_T_EE = data.O_T_F * p.F_T_EE;
  data.O_T_K = data.O_T_EE * p.EE_T_K;
}

const Transform& frame_pose(const Data& data, Frame frame) {
  switch (frame) {
    case Frame::kFlange: return data.O_T_F;
    case Frame::kEndEffector: return data.O_T_EE;
    case Frame::kStiffness: return data.O_T_K;
    default: return data.O_T_joint[static_cast<int>(frame)];
  }
}

void zero_jacobian(const Data& data, Frame frame, Matrix6x7& jacobian) {
  const Vector3& p = frame_pose(data, frame).translation;
  const int n = moving_joints(frame);
  for (int j = 0; j < n; ++j) {
    const Vector6& S = data.axis[j];
    // Velocity of the point p: u + w x p (paper eq. 2: z_j x (p - o_j)).
    jacobian.col(j) << S.head<3>() + S.tail<3>().cross(p), S.tail<3>();
  }
  jacobian.rightCols(kNumJoints - n).setZero();   // joints beyond the frame's link do not move it
}

Matrix3x7 point_jacobian(const Data& data, int link, const Vector3& point) {
  Matrix3x7 jacobian = Matrix3x7::Zero();
  for (int j = 0; j < link; ++j) jacobian.col(j) = data.axis[j].head<3>() + data.axis[j].tail<3>().cross(point);
  return jacobian;
}

void body_jacobian(const Data& data, Frame frame, Matrix6x7& jacobian) {
  zero_jacobian(data, frame, jacobian);
  const Matrix3 R_transpose = frame_pose(data, frame).rotation.transpose();
  jacobian.topRows<3>() = R_transpose * jacobian.topRows<3>();
  jacobian.bottomRows<3>() = R_transpose * jacobian.bottomRows<3>();
}

void zero_jacobian_time_derivative(const Data& data, Frame frame, const Vector7& dq, Matrix6x7& jacobian_dot) {
  const Vector3& p = frame_pose(data, frame).translation;
  const int n = moving_joints(frame);
  Vector6 frame_velocity = Vector6::Zero();   // spatial velocity of the body carrying the frame
  for (int j = 0; j < n; ++j) frame_velocity += data.axis[j] * dq[j];
  const Vector3 p_dot = frame_velocity.head<3>() + frame_velocity.tail<3>().cross(p);

  jacobian_dot.setZero();
  Vector6 v = Vector6::Zero();
  for (int j = 0; j < n; ++j) {
    const Vector6& S = data.axis[j];
    v += S * dq[j];
    const Vector6 S_dot = cross_motion(v, S);   // the axis moves with body j
    jacobian_dot.col(j) << S_dot.head<3>() + S_dot.tail<3>().cross(p) + S.tail<3>().cross(p_dot), S_dot.tail<3>();
  }
}

}  // namespace csp
