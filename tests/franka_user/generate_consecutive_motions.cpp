// Five joint velocity motions in a row with low collision thresholds; a motion that ends in a
// reflex is followed by Robot::automaticErrorRecovery and the next motion.
//
// Warning: the robot moves; make sure there is enough space in front of and beside it.
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

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);

    // Half the usual thresholds: a collision reflex is likely, and part of what this shows.
    const std::array<double, 7> torque{{10.0, 10.0, 9.0, 9.0, 8.0, 7.0, 6.0}};
    const std::array<double, 6> force{{10.0, 10.0, 10.0, 12.5, 12.5, 12.5}};
    robot.setCollisionBehavior(torque, torque, torque, torque, force, force, force, force);

    for (int motion = 0; motion < 5; ++motion) {
      std::cout << "Executing motion." << std::endl;
      try {
        robot.control(
            JointVelocityWave(0.2, 4.0, {{false, false, true, false, false, false, false}}));
      } catch (const franka::ControlException& e) {
        std::cout << e.what() << std::endl;
        std::cout << "Running error recovery..." << std::endl;
        robot.automaticErrorRecovery();
      }
    }
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }

  std::cout << "Finished." << std::endl;
  return 0;
}
