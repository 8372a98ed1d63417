// The Cartesian pose motion of generate_cartesian_pose_motion (from the commanded O_T_EE_c) with
// the external control loop of libfranka 0.15: the program itself reads each state with readOnce
// and writes each command with writeOnce, instead of handing Robot::control a callback.
//
// Warning: the robot moves; make sure there is enough space in front of it.
#include <iostream>

#include <franka/active_control.h>
#include <franka/active_motion_generator.h>
#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"
#include "external_control_loop.h"

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
    auto active_control = robot.startCartesianPoseControl(
        research_interface::robot::Move::ControllerMode::kJointImpedance);
    runExternalControlLoop(*active_control, CartesianArc(&franka::RobotState::O_T_EE_c));
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
