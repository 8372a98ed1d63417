// The joint velocity motion of generate_joint_velocity_motion with the external control loop of libfranka 0.15: the program itself reads each state with
// readOnce and writes each command with writeOnce, instead of handing Robot::control a callback.
//
// Warning: the robot moves; make sure there is enough space in front of it.
#include <iostream>

#include <franka/active_control.h>
#include <franka/active_motion_generator.h>
#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);

    setMotionCollisionBehavior(robot);
    auto motion = JointVelocityWave(1.0, 1.0, {{false, false, false, true, true, true, true}});
    auto active_control =
        robot.startJointVelocityControl(research_interface::robot::Move::ControllerMode::kJointImpedance);
    bool motion_finished = false;
    while (!motion_finished) {
      const auto [robot_state, period] = active_control->readOnce();
      const auto command = motion(robot_state, period);
      motion_finished = command.motion_finished;
      active_control->writeOnce(command);
    }
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
