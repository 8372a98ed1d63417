// The external control loop's common part (libfranka 0.15's ActiveControl): reading states with
// their period, and the motion's end when the handle goes away unfinished (the motion stops).
// The timing rules are the robot's (docs/franka_api.md, "External control loop"): one writeOnce
// per state read, a state not answered in its cycle is a lost command, 20 lost in a row end the
// motion in communication_constraints_violation. Needs C++17.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "franka/active_control_base.h"
#include "franka/exception.h"
#include "franka/robot.h"

namespace franka {

class ActiveControl : public ActiveControlBase {
 public:
  ~ActiveControl() override;

  std::pair<RobotState, Duration> readOnce() override;

  // The overloads that do not fit this motion's kind throw ControlException.
  void writeOnce(const Torques& /* control_input */) override { wrongWriteOnce(); }
  void writeOnce(const JointPositions& /* motion_generator_input */,
                 const std::optional<const Torques>& /* control_input */) override {
    wrongWriteOnce();
  }
  void writeOnce(const JointVelocities& /* motion_generator_input */,
                 const std::optional<const Torques>& /* control_input */) override {
    wrongWriteOnce();
  }
  void writeOnce(const CartesianPose& /* motion_generator_input */,
                 const std::optional<const Torques>& /* control_input */) override {
    wrongWriteOnce();
  }
  void writeOnce(const CartesianVelocities& /* motion_generator_input */,
                 const std::optional<const Torques>& /* control_input */) override {
    wrongWriteOnce();
  }
  void writeOnce(const JointPositions& motion_generator_input) override {
    writeOnce(motion_generator_input, std::optional<const Torques>());
  }
  void writeOnce(const JointVelocities& motion_generator_input) override {
    writeOnce(motion_generator_input, std::optional<const Torques>());
  }
  void writeOnce(const CartesianPose& motion_generator_input) override {
    writeOnce(motion_generator_input, std::optional<const Torques>());
  }
  void writeOnce(const CartesianVelocities& motion_generator_input) override {
    writeOnce(motion_generator_input, std::optional<const Torques>());
  }

 protected:
  ActiveControl(std::shared_ptr<Robot::Impl> robot_impl, uint32_t motion_id);

  [[noreturn]] static void wrongWriteOnce();

  std::shared_ptr<Robot::Impl> robot_impl;   // NOLINT(readability-identifier-naming): libfranka's names
  uint32_t motion_id;
  bool control_finished = false;
  std::optional<Duration> last_read_access;
};

}  // namespace franka
