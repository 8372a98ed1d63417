// What control callbacks return: joint torques, or the joint positions / velocities of a motion
// generator, each able to end the motion (libfranka's control_types.h).
#pragma once

#include <algorithm>
#include <array>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include <type_traits>

namespace franka {

// The robot's controller that tracks a motion generator. CSP's emulated robot has the joint
// impedance one only: Robot::control rejects kCartesianImpedance.
enum class ControllerMode { kJointImpedance, kCartesianImpedance };

// kEnforce: control() fails without real-time scheduling; kIgnore: it warns and goes on.
enum class RealtimeConfig { kEnforce, kIgnore };

// Set motion_finished to end the motion after this command (see MotionFinished).
struct Finishable {
  bool motion_finished = false;
};

namespace detail {
inline std::array<double, 7> seven_values(std::initializer_list<double> values, const char* what) {
  if (values.size() != 7)
    throw std::invalid_argument(std::string(what) + ": expected 7 values, got " + std::to_string(values.size()));
  std::array<double, 7> out{};
  std::copy(values.begin(), values.end(), out.begin());
  return out;
}
}  // namespace detail

// Joint torques without gravity (the robot adds it) and without friction [N m].
class Torques : public Finishable {
 public:
  Torques(const std::array<double, 7>& torques) noexcept : tau_J(torques) {}   // NOLINT: implicit as in libfranka
  Torques(std::initializer_list<double> torques) : tau_J(detail::seven_values(torques, "Torques")) {}
  std::array<double, 7> tau_J{};   // NOLINT(readability-identifier-naming)
};

// Desired joint positions [rad].
class JointPositions : public Finishable {
 public:
  JointPositions(const std::array<double, 7>& joint_positions) noexcept : q(joint_positions) {}   // NOLINT
  JointPositions(std::initializer_list<double> joint_positions)
      : q(detail::seven_values(joint_positions, "JointPositions")) {}
  std::array<double, 7> q{};
};

// Desired joint velocities [rad/s].
class JointVelocities : public Finishable {
 public:
  JointVelocities(const std::array<double, 7>& joint_velocities) noexcept : dq(joint_velocities) {}   // NOLINT
  JointVelocities(std::initializer_list<double> joint_velocities)
      : dq(detail::seven_values(joint_velocities, "JointVelocities")) {}
  std::array<double, 7> dq{};
};

// The same command, marked as the motion's last.
template <typename Command, typename = typename std::enable_if<std::is_base_of<Finishable, Command>::value>::type>
Command MotionFinished(Command command) noexcept {   // NOLINT(readability-identifier-naming)
  command.motion_finished = true;
  return command;
}

}  // namespace franka
