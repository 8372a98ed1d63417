// What the robot does with a Cartesian command before its joint controllers see it: pose
// arithmetic on commanded poses and twists, the elbow, and the robot's own inverse kinematics
// (docs/emulator.md, "Cartesian motion generators").
#pragma once

#include <array>
#include <string>

#include "csp/dynamics/algorithms.hpp"

namespace csp::rt {

// The joint-4 angle at which the elbow flips (libfranka control_types.h, CartesianVelocities::elbow:
// alpha = -0.467002423653011 rad). It is where the arm is stretched: with the 0.0825 m offsets of
// joints 4 and 5 from the upper arm (d3 = 0.316 m) and the forearm (d5 = 0.384 m),
// -(atan(0.0825/0.316) + atan(0.0825/0.384)) = -0.4670 rad; the two elbow configurations of one
// joint-3 position meet there (tests/test_emulator_cartesian.cpp checks this on the model).
inline constexpr double kElbowFlip = -0.467002423653011;

// The elbow's sign as libfranka defines it: +1 if q4 > kElbowFlip, -1 if below, 0 on it.
double elbow_sign(double q4);

// The rotation vector (axis times angle, |angle| <= pi) of R, and the rotation of a rotation vector.
Vector3 rotation_log(const Matrix3& R);
Matrix3 rotation_exp(const Vector3& rotation_vector);

// The twist that moves `from` to `to` in dt: linear (p_to - p_from) / dt; angular log(R_to R_from^T) / dt,
// base-frame axes about the EE origin (the axes of franka::CartesianVelocities).
Vector6 pose_twist(const Transform& from, const Transform& to, double dt);
// The pose reached from `pose` with `twist` held for dt: p + v dt, exp(w dt) R.
Transform advance_pose(const Transform& pose, const Vector6& twist, double dt);

// Why a commanded 4x4 column-major pose is not a homogeneous transformation, or empty: bottom row
// (0 0 0 1), finite, and every row and column of the rotation a unit vector within 1e-5 (libfranka
// control_tools.h isHomogeneousTransformation, kOrthonormalThreshold), with determinant +1.
std::string homogeneous_pose_problem(const std::array<double, 16>& O_T_EE);

// The robot's inverse kinematics with the elbow as the redundancy parameter. Franka's elbow
// (libfranka control_types.h) is joint 3's position plus the sign of joint 4 relative to
// kElbowFlip. With q3 held, the remaining six joints (1, 2, 4, 5, 6, 7) determine the EE pose
// locally one-to-one, so the elbow fixes the redundant degree of freedom exactly as Franka's
// definition does; the sign of q4 picks the branch, and damped Newton steps from the previous
// commanded q stay on that branch (the pose moves at most a few mm per 1 ms cycle).
// Each step: e = (p_d - p(q); log(R_d R(q)^T)), J6 the 6x6 EE Jacobian without column 3,
// dq6 = (J6^T J6 + lambda^2 1)^-1 J6^T e.
struct InverseKinematics {
  Vector7 q = Vector7::Zero();
  double position_error = 0.0;      // [m] |p_d - p(q)| at the result
  double orientation_error = 0.0;   // [rad] |log(R_d R(q)^T)|
  int iterations = 0;
  bool converged = false;           // both within kInverseKinematicsTolerance
};
inline constexpr double kInverseKinematicsTolerance = 1e-10;   // [m] and [rad]
InverseKinematics inverse_kinematics(const Model& model, Data& data, const Transform& O_T_EE, double q3,
                                     const Vector7& q_start);

}  // namespace csp::rt
