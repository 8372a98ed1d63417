// What control callbacks return: joint torques, or the joint positions / velocities, Cartesian
// pose / velocities of a motion generator, each able to end the motion (libfranka's
// control_types.h, the same classes and constructors). Self-contained, C++14.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>
#include <stdexcept>
#include <string>

namespace franka {

// The robot's controller that tracks a motion generator: its joint impedance
// (Robot::setJointImpedance) or its Cartesian impedance on the stiffness frame K
// (Robot::setCartesianImpedance).
enum class ControllerMode { kJointImpedance, kCartesianImpedance };

// kEnforce: control() fails without real-time scheduling; kIgnore: it goes on without. On CSP's
// lockstep clock the robot waits for each command, so neither needs real-time scheduling.
enum class RealtimeConfig { kEnforce, kIgnore };

// Set motion_finished to end the motion after this command (see MotionFinished).
struct Finishable {
  bool motion_finished = false;
};

namespace detail {
// Copies `values` into `out`; libfranka's std::invalid_argument when the count is wrong.
template <std::size_t N>
void copy_exactly(std::initializer_list<double> values, std::array<double, N>& out, const char* name) {
  if (values.size() != N) throw std::invalid_argument(std::string("Invalid number of elements in ") + name + ".");
  std::copy(values.begin(), values.end(), out.begin());
}
}  // namespace detail

// Joint torques without gravity (the robot adds it) and without friction [N m].
class Torques : public Finishable {
 public:
  Torques(const std::array<double, 7>& torques) noexcept : tau_J(torques) {}   // NOLINT: implicit as in libfranka
  Torques(std::initializer_list<double> torques) { detail::copy_exactly(torques, tau_J, "tau_J"); }
  std::array<double, 7> tau_J{};   // NOLINT(readability-identifier-naming)
};

// Desired joint positions [rad].
class JointPositions : public Finishable {
 public:
  JointPositions(const std::array<double, 7>& joint_positions) noexcept : q(joint_positions) {}   // NOLINT
  JointPositions(std::initializer_list<double> joint_positions) { detail::copy_exactly(joint_positions, q, "joint_positions"); }
  std::array<double, 7> q{};
};

// Desired joint velocities [rad/s].
class JointVelocities : public Finishable {
 public:
  JointVelocities(const std::array<double, 7>& joint_velocities) noexcept : dq(joint_velocities) {}   // NOLINT
  JointVelocities(std::initializer_list<double> joint_velocities) {
    detail::copy_exactly(joint_velocities, dq, "joint_velocities");
  }
  std::array<double, 7> dq{};
};

// Desired end-effector pose O_T_EE in the base frame (4x4, column-major) and, optionally, the elbow:
// joint 3's position [rad] and the sign of joint 4 (+1 or -1). All zeros: no elbow given.
class CartesianPose : public Finishable {
 public:
  CartesianPose(const std::array<double, 16>& cartesian_pose) noexcept : O_T_EE(cartesian_pose) {}   // NOLINT
  CartesianPose(const std::array<double, 16>& cartesian_pose, const std::array<double, 2>& elbow) noexcept
      : O_T_EE(cartesian_pose), elbow(elbow) {}
  CartesianPose(std::initializer_list<double> cartesian_pose) { detail::copy_exactly(cartesian_pose, O_T_EE, "cartesian_pose"); }
  CartesianPose(std::initializer_list<double> cartesian_pose, std::initializer_list<double> elbow) {
    detail::copy_exactly(cartesian_pose, O_T_EE, "cartesian_pose");
    detail::copy_exactly(elbow, this->elbow, "elbow");
  }
  std::array<double, 16> O_T_EE{};   // NOLINT(readability-identifier-naming)
  std::array<double, 2> elbow{};
  bool hasElbow() const noexcept { return elbow != std::array<double, 2>{}; }
};

// Desired end-effector twist O_dP_EE in the base frame [m/s x3, rad/s x3] and, optionally, the elbow.
class CartesianVelocities : public Finishable {
 public:
  CartesianVelocities(const std::array<double, 6>& cartesian_velocities) noexcept   // NOLINT
      : O_dP_EE(cartesian_velocities) {}
  CartesianVelocities(const std::array<double, 6>& cartesian_velocities, const std::array<double, 2>& elbow) noexcept
      : O_dP_EE(cartesian_velocities), elbow(elbow) {}
  CartesianVelocities(std::initializer_list<double> cartesian_velocities) {
    detail::copy_exactly(cartesian_velocities, O_dP_EE, "cartesian_velocities");
  }
  CartesianVelocities(std::initializer_list<double> cartesian_velocities, std::initializer_list<double> elbow) {
    detail::copy_exactly(cartesian_velocities, O_dP_EE, "cartesian_velocities");
    detail::copy_exactly(elbow, this->elbow, "elbow");
  }
  std::array<double, 6> O_dP_EE{};   // NOLINT(readability-identifier-naming)
  std::array<double, 2> elbow{};
  bool hasElbow() const noexcept { return elbow != std::array<double, 2>{}; }
};

// The same command, marked as the motion's last.
inline Torques MotionFinished(Torques command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}
inline JointPositions MotionFinished(JointPositions command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}
inline JointVelocities MotionFinished(JointVelocities command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}
inline CartesianPose MotionFinished(CartesianPose command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}
inline CartesianVelocities MotionFinished(CartesianVelocities command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}

}  // namespace franka
