// The external control loop's handle (libfranka 0.15's ActiveControlBase): a program that runs
// its own loop calls readOnce() for each of the robot's states and answers it with one
// writeOnce(). Needs C++17 (std::optional in libfranka's writeOnce signatures).
#pragma once

#if __cplusplus < 201703L
#error "franka/active_control_base.h needs C++17: libfranka's writeOnce takes std::optional"
#endif

#include <memory>
#include <optional>
#include <utility>

#include "franka/control_types.h"
#include "franka/duration.h"
#include "franka/exception.h"
#include "franka/robot_state.h"

namespace franka {

class ActiveControlBase {
 public:
  virtual ~ActiveControlBase() = default;

  // The robot's next state and the robot time since the previous readOnce (0 at the first).
  // Throws ControlException once the motion has ended in a reflex or was stopped.
  virtual std::pair<RobotState, Duration> readOnce() = 0;

  // The answer to the state last read: torques (startTorqueControl), or the motion generator's
  // command, with the program's torques when the motion runs kExternalController.
  virtual void writeOnce(const Torques& control_input) = 0;
  virtual void writeOnce(const JointPositions& motion_generator_input,
                         const std::optional<const Torques>& control_input) = 0;
  virtual void writeOnce(const JointVelocities& motion_generator_input,
                         const std::optional<const Torques>& control_input) = 0;
  virtual void writeOnce(const CartesianPose& motion_generator_input,
                         const std::optional<const Torques>& control_input) = 0;
  virtual void writeOnce(const CartesianVelocities& motion_generator_input,
                         const std::optional<const Torques>& control_input) = 0;
  virtual void writeOnce(const JointPositions& motion_generator_input) = 0;
  virtual void writeOnce(const JointVelocities& motion_generator_input) = 0;
  virtual void writeOnce(const CartesianPose& motion_generator_input) = 0;
  virtual void writeOnce(const CartesianVelocities& motion_generator_input) = 0;

 protected:
  ActiveControlBase() = default;
};

}  // namespace franka
