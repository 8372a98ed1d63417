// Joint velocity motion with Robot::control: joints 4 to 7 turn one way and back in 2 s.
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
    robot.control(JointVelocityWave(1.0, 1.0, {{false, false, false, true, true, true, true}}));
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
