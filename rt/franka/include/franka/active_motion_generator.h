// The external control loop of a motion generator (Robot::startJointPositionControl and the
// others), with the program's torques when it runs kExternalController. Needs C++17.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "franka/active_control.h"

namespace franka {

template <typename MotionGeneratorType>
class ActiveMotionGenerator : public ActiveControl {
 public:
  using ActiveControl::writeOnce;
  // The command for the state last read. Torques must come exactly when the motion runs
  // kExternalController (ControlException otherwise). MotionFinished on either ends the motion.
  void writeOnce(const MotionGeneratorType& motion_generator_input,
                 const std::optional<const Torques>& control_input) override;

  friend class Robot;

 private:
  ActiveMotionGenerator(std::shared_ptr<Robot::Impl> robot_impl, uint32_t motion_id,
                        research_interface::robot::Move::ControllerMode controller_type)
      : ActiveControl(std::move(robot_impl), motion_id), controller_type_(controller_type) {}

  research_interface::robot::Move::ControllerMode controller_type_;
};

extern template class ActiveMotionGenerator<JointPositions>;
extern template class ActiveMotionGenerator<JointVelocities>;
extern template class ActiveMotionGenerator<CartesianPose>;
extern template class ActiveMotionGenerator<CartesianVelocities>;

}  // namespace franka
