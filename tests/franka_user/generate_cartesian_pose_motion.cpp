// Cartesian pose motion with Robot::control: the end effector travels a quarter circle in the x-z
// plane and back in 10 s, starting from the measured pose O_T_EE.
//
// Warning: the robot moves; make sure there is enough space in front of it.
#include <iostream>

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
    robot.control(CartesianArc(&franka::RobotState::O_T_EE));
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
