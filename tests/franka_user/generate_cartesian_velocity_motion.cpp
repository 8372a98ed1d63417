// Cartesian velocity motion with Robot::control: the end effector moves down and forward at
// 45 degrees and back, 4 s each way.
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

    setCartesianVelocityBehavior(robot);
    robot.control(CartesianVelocityWave());
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
