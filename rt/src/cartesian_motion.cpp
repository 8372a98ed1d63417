// The robot's Cartesian motion generators and its Cartesian impedance controller: the pose
// arithmetic, the inverse kinematics, the cartesian_motion_generator_* checks, and the torque
// that holds the stiffness frame K on its target.
#include "csp/rt/cartesian_motion.hpp"

#include <cmath>
#include <sstream>

#include "csp/dynamics/arrays.hpp"
#include "csp/rt/emulator.hpp"

namespace csp::rt {
namespace {

constexpr double kOrthonormalThreshold = 1e-5; // libfranka control_tools.h isHomogeneousTransformation
constexpr double kNewtonDamping = 1e-6;        // lambda of the damped Newton step [m or rad]
constexpr int kMaxInverseKinematicsIterations = 20;
constexpr double kProjectionDamping = 1e-3;    // (J J^T + lambda^2 1)^-1 in the null-space projector
constexpr double kInertiaDamping = 1e-6;       // regularises J M^-1 J^T near singularities

// The EE pose error of the robot's model at q: (p_d - p; log(R_d R^T)), base frame.
Vector6 pose_error(const Data& data, const Transform& O_T_EE_d) {
  const Transform& O_T_EE = data.O_T_EE;
  return linear_angular(O_T_EE_d.translation - O_T_EE.translation,
                        rotation_log(O_T_EE_d.rotation * O_T_EE.rotation.transpose()));
}

// A 6-vector's two halves rotated by R (into the frame R maps from when R^T is given).
Vector6 rotate(const Matrix3& R, const Vector6& v) { return linear_angular(R * v.head<3>(), R * v.tail<3>()); }

}  // namespace

double elbow_sign(double q4) { return q4 > kElbowFlip ? 1.0 : (q4 < kElbowFlip ? -1.0 : 0.0); }

Vector3 rotation_log(const Matrix3& R) {
  const Eigen::AngleAxisd angle_axis(R);   // via the quaternion: accurate for small angles too
  return angle_axis.angle() * angle_axis.axis();
}

Matrix3 rotation_exp(const Vector3& rotation_vector) {
  const double angle = rotation_vector.norm();
  if (angle == 0.0) return Matrix3::Identity();
  return Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
}

Vector6 pose_twist(const Transform& from, const Transform& to, double dt) {
  return linear_angular((to.translation - from.translation) / dt,
                        rotation_log(to.rotation * from.rotation.transpose()) / dt);
}

Transform advance_pose(const Transform& pose, const Vector6& twist, double dt) {
  return {rotation_exp(twist.tail<3>() * dt) * pose.rotation, pose.translation + twist.head<3>() * dt};
}

std::string homogeneous_pose_problem(const std::array<double, 16>& O_T_EE) {
  const Eigen::Matrix4d m = from_array<Eigen::Matrix4d>(O_T_EE);
  if (!m.allFinite()) return "expected finite values";
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) return "expected the bottom row 0 0 0 1";
  const Matrix3 R = m.topLeftCorner<3, 3>();
  if (((R.colwise().norm().array() - 1.0).abs() > kOrthonormalThreshold).any() ||
      ((R.rowwise().norm().array() - 1.0).abs() > kOrthonormalThreshold).any())
    return "expected unit rows and columns of the rotation (within 1e-5)";
  if (R.determinant() < 0.0) return "expected a rotation, not a reflection (determinant +1)";
  return {};
}

InverseKinematics inverse_kinematics(const Model& model, Data& data, const Transform& O_T_EE, double q3,
                                     const Vector7& q_start) {
  constexpr std::array<int, 6> kFreeJoints{0, 1, 3, 4, 5, 6};   // joint 3 is the elbow, held
  InverseKinematics result;
  result.q = q_start;
  result.q[2] = q3;
  Matrix6x7 J;
  Matrix6 J6;
  for (;; ++result.iterations) {
    forward_kinematics(model, data, result.q);
    const Vector6 error = pose_error(data, O_T_EE);
    result.position_error = error.head<3>().norm();
    result.orientation_error = error.tail<3>().norm();
    result.converged = result.position_error <= kInverseKinematicsTolerance &&
                       result.orientation_error <= kInverseKinematicsTolerance;
    if (result.converged || result.iterations == kMaxInverseKinematicsIterations || !error.allFinite()) return result;
    zero_jacobian(data, Frame::kEndEffector, J);
    for (int c = 0; c < 6; ++c) J6.col(c) = J.col(kFreeJoints[c]);
    const Vector6 step =
        (J6.transpose() * J6 + kNewtonDamping * kNewtonDamping * Matrix6::Identity()).ldlt().solve(J6.transpose() * error);
    for (int c = 0; c < 6; ++c) result.q[kFreeJoints[c]] += step[c];
  }
}

// A Cartesian pose or velocity command as the robot takes it. The commanded pose (a pose command,
// or the last pose advanced by a velocity command; a lost command is extrapolated with constant
// acceleration) and elbow give the commanded twist and acceleration by backward differences of
// successive commands, the way libfranka's limitRate reads them back from O_T_EE_c, O_dP_EE_c,
// O_ddP_EE_c and elbow_c, delbow_c, ddelbow_c (src/control_loop.cpp, rate_limiting.h). Their
// norms (translation, rotation) and the elbow's rates are checked against the robot's Cartesian
// limits, velocity -> _velocity_limits_violation, acceleration -> _velocity_discontinuity, jerk
// -> _acceleration_discontinuity, like the joint checks. Then the inverse kinematics from the
// last commanded joints gives q_c; the caller checks it like a joint command.
ErrorSet Emulator::cartesian_setpoint(const Command* command, Vector7& q_c, Vector7& dq_c) {
  const CartesianLimits& limits = plant_.parameters().cartesian_limits;
  const JointLimits& joint_limits = plant_.parameters().joint_limits;
  MotionGenerator& g = motion_generator_;
  ErrorSet errors;

  Transform pose;
  Vector6 twist;
  double elbow = g.elbow_c, sign = g.elbow_sign;
  if (!command) {
    twist = g.O_dP_EE_c + g.O_ddP_EE_c * kDeltaT;
    pose = advance_pose(g.O_T_EE_c, twist, kDeltaT);
    elbow += (g.delbow_c + g.ddelbow_c * kDeltaT) * kDeltaT;
  } else if (*mode_ == ControlMode::kCartesianPose) {
    if (!homogeneous_pose_problem(command->O_T_EE_c).empty()) {
      errors.set(Error::cartesian_position_motion_generator_invalid_frame);
      motion_generator_reason_ = "cartesian_position_motion_generator_invalid_frame: the commanded O_T_EE: " +
                                 homogeneous_pose_problem(command->O_T_EE_c);
      return errors;
    }
    pose = transform_from_array(command->O_T_EE_c);
    twist = pose_twist(g.O_T_EE_c, pose, kDeltaT);
  } else {
    twist = from_array<Vector6>(command->O_dP_EE_c);
    pose = advance_pose(g.O_T_EE_c, twist, kDeltaT);
  }
  if (command && command->elbow) {
    elbow = (*command->elbow)[0];
    sign = (*command->elbow)[1];
  }

  // The first command starts the motion where the robot stands: a pose and an elbow within one
  // cycle at the maximum velocity of the held ones are taken as the start, at rest (libfranka's
  // examples start from the measured O_T_EE and elbow, which the held pose tracks closely).
  if (command && g.first_command) {
    if (*mode_ == ControlMode::kCartesianPose && (twist.head<3>().norm() > limits.translation.v_max + kLimitTolerance ||
                                                  twist.tail<3>().norm() > limits.rotation.v_max + kLimitTolerance))
      errors.set(Error::cartesian_position_motion_generator_start_pose_invalid);
    if (command->elbow && sign != g.elbow_sign) errors.set(Error::start_elbow_sign_inconsistent);
    else if (command->elbow && std::abs(elbow - g.elbow_c) > limits.elbow.v_max * kDeltaT + kLimitTolerance)
      errors.set(Error::cartesian_motion_generator_start_elbow_invalid);
    if (errors) return errors;
    if (*mode_ == ControlMode::kCartesianPose) {
      g.O_T_EE_c = pose;
      twist.setZero();
    }
    g.elbow_c = elbow;
  }
  if (sign != g.elbow_sign) errors.set(Error::cartesian_motion_generator_elbow_sign_inconsistent);
  if (elbow < joint_limits.q_min[2] - kLimitTolerance || elbow > joint_limits.q_max[2] + kLimitTolerance)
    errors.set(Error::cartesian_motion_generator_elbow_limit_violation);

  const Vector6 acceleration = (twist - g.O_dP_EE_c) / kDeltaT;
  const Vector6 jerk = (acceleration - g.O_ddP_EE_c) / kDeltaT;
  const double delbow = (elbow - g.elbow_c) / kDeltaT;
  const double ddelbow = (delbow - g.delbow_c) / kDeltaT;
  const double dddelbow = (ddelbow - g.ddelbow_c) / kDeltaT;
  const auto check = [&errors](double velocity, double acceleration, double jerk, const CartesianLimits::Axis& axis) {
    if (velocity > axis.v_max + kLimitTolerance) errors.set(Error::cartesian_motion_generator_velocity_limits_violation);
    if (acceleration > axis.a_max + kLimitTolerance) errors.set(Error::cartesian_motion_generator_velocity_discontinuity);
    if (jerk > axis.j_max + kLimitTolerance) errors.set(Error::cartesian_motion_generator_acceleration_discontinuity);
  };
  check(twist.head<3>().norm(), acceleration.head<3>().norm(), jerk.head<3>().norm(), limits.translation);
  check(twist.tail<3>().norm(), acceleration.tail<3>().norm(), jerk.tail<3>().norm(), limits.rotation);
  check(std::abs(delbow), std::abs(ddelbow), std::abs(dddelbow), limits.elbow);
  if (errors) return errors;

  const InverseKinematics ik = inverse_kinematics(internal_, internal_data_, pose, elbow, g.q_c);
  if (!ik.converged) {
    // No joint configuration near the last one reaches the pose (out of reach, or through a
    // singularity): the joints would have to jump.
    errors.set(Error::cartesian_motion_generator_joint_velocity_limits_violation);
    std::ostringstream why;
    why << "cartesian_motion_generator_joint_velocity_limits_violation: no inverse kinematics solution near the last "
           "commanded joints (left " << ik.position_error << " m, " << ik.orientation_error << " rad)";
    motion_generator_reason_ = why.str();
    return errors;
  }
  if (elbow_sign(ik.q[3]) != sign) errors.set(Error::cartesian_motion_generator_elbow_sign_inconsistent);
  if (errors) return errors;

  q_c = ik.q;
  if (command && g.first_command) g.q_c = q_c;   // the start, at rest
  dq_c = (q_c - g.q_c) / kDeltaT;
  g.O_T_EE_c = pose;
  g.O_ddP_EE_c = acceleration;
  g.O_dP_EE_c = twist;
  g.elbow_c = elbow;
  g.ddelbow_c = ddelbow;
  g.delbow_c = delbow;
  g.elbow_sign = sign;
  return errors;
}

// The Cartesian impedance's target and damping at the start of a cycle. Critical damping per
// K axis from the diagonal of the Cartesian inertia Lambda = (J M^-1 J^T)^-1 (Khatib's
// operational-space inertia) in K axes: d_i = 2 sqrt(k_i Lambda_ii), as the joint impedance uses
// the joint inertia's diagonal. Needs the mass matrix at the arm's q in internal_data_.
Emulator::CartesianImpedance Emulator::cartesian_impedance_target(const Vector7& q_c, const Vector7& dq_c) {
  Matrix6x7 J;
  forward_kinematics(internal_, internal_data_, plant_state_.q);
  zero_jacobian(internal_data_, Frame::kStiffness, J);
  const Matrix3 R = internal_data_.O_T_K.rotation;
  const Eigen::Matrix<double, kNumJoints, 6> M_inverse_Jt = internal_data_.mass_matrix.llt().solve(J.transpose());
  const Matrix6 Lambda = (J * M_inverse_Jt + kInertiaDamping * Matrix6::Identity()).inverse();
  Matrix6 R6 = Matrix6::Zero();
  R6.topLeftCorner<3, 3>() = R6.bottomRightCorner<3, 3>() = R;
  const Vector6 Lambda_K = (R6.transpose() * Lambda * R6).diagonal();

  CartesianImpedance target;
  target.damping = 2.0 * settings_.cartesian_stiffness.cwiseProduct(Lambda_K.cwiseMax(0.0)).cwiseSqrt();
  forward_kinematics(internal_, internal_data_, q_c);
  zero_jacobian(internal_data_, Frame::kStiffness, J);
  target.O_T_K_d = internal_data_.O_T_K;
  target.O_dP_K_d = J * dq_c;
  return target;
}

// The wrench on K that pulls it to its target, F_K = K e_K + D (v_d - v)_K in K axes (the
// stiffness acts along K: libfranka robot.h, setK), mapped to joint torques by J_K^T; the null
// space of J_K (the elbow) is held at q_c by the joint impedance, projected with
// N = 1 - J^T (J J^T + lambda^2 1)^-1 J so that it does not fight the Cartesian task.
Vector7 Emulator::cartesian_impedance_torque(const CartesianImpedance& target, const Vector7& q_c,
                                             const Vector7& dq_c, const Vector7& joint_damping) {
  const PlantState& arm = plant_state_;
  Matrix6x7 J;
  forward_kinematics(internal_, internal_data_, arm.q);
  zero_jacobian(internal_data_, Frame::kStiffness, J);
  const Transform& O_T_K = internal_data_.O_T_K;
  const Matrix3 R_transpose = O_T_K.rotation.transpose();
  const Vector6 error = linear_angular(target.O_T_K_d.translation - O_T_K.translation,
                                       rotation_log(target.O_T_K_d.rotation * O_T_K.rotation.transpose()));
  const Vector6 velocity_error = target.O_dP_K_d - J * arm.dq;
  const Vector6 K_F = settings_.cartesian_stiffness.cwiseProduct(rotate(R_transpose, error)) +
                      target.damping.cwiseProduct(rotate(R_transpose, velocity_error));
  const Vector6 O_F = rotate(O_T_K.rotation, K_F);

  const Matrix6 JJt = J * J.transpose() + kProjectionDamping * kProjectionDamping * Matrix6::Identity();
  const Matrix6x7 JJt_inverse_J = JJt.ldlt().solve(J);
  const Matrix7 N = Matrix7::Identity() - J.transpose() * JJt_inverse_J;
  const Vector7 joint = settings_.joint_stiffness.cwiseProduct(q_c - arm.q) + joint_damping.cwiseProduct(dq_c - arm.dq);
  return J.transpose() * O_F + N * joint;
}

}  // namespace csp::rt
