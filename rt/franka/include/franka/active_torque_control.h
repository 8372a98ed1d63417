// The external control loop of a torque motion (Robot::startTorqueControl). Needs C++17.
#pragma once

#include <cstdint>
#include <memory>

#include "franka/active_control.h"

namespace franka {

class ActiveTorqueControl : public ActiveControl {
 public:
  using ActiveControl::writeOnce;
  // The torques for the state last read; MotionFinished ends the motion.
  void writeOnce(const Torques& control_input) override;

  friend class Robot;

 private:
  ActiveTorqueControl(std::shared_ptr<Robot::Impl> robot_impl, uint32_t motion_id)
      : ActiveControl(std::move(robot_impl), motion_id) {}
};

}  // namespace franka
