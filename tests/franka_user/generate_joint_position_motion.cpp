// Joint position motion with Robot::control: three joints swing out and back in 5 s.
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

    // Parameters are set before a control loop, never inside one.
    setMotionCollisionBehavior(robot);
    robot.control(JointPositionWave(&franka::RobotState::q));
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
