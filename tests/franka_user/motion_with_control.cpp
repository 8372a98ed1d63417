// A joint velocity motion generator and a torque controller in one Robot::control call: the robot
// turns joint 4 along a smooth velocity profile while the program's PD controller tracks the
// robot's q_d. If the motion ends in an error, the log the ControlException carries is written to
// a CSV file.
//
// Warning: the robot moves; make sure there is enough space in front of it.
#include <array>
#include <iostream>

#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  // NOLINTNEXTLINE(readability-identifier-naming)
  const std::array<double, 7> K_P{{200.0, 200.0, 200.0, 200.0, 200.0, 200.0, 200.0}};
  // NOLINTNEXTLINE(readability-identifier-naming)
  const std::array<double, 7> K_D{{10.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0}};

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);

    setMotionCollisionBehavior(robot);
    robot.control(JointPdController(K_P, K_D), JointVelocityRamp(3, 1.0));
  } catch (const franka::ControlException& e) {
    std::cout << e.what() << std::endl;
    writeLogToFile(e.log);
    return -1;
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
