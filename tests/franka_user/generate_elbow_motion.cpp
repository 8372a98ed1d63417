// Elbow motion with Robot::control: the end effector holds its pose while the elbow (the first
// elbow parameter, joint 3's angle) swings by up to pi/5 and back in 10 s.
//
// Warning: the robot moves; make sure the elbow has space around it.
#include <array>
#include <cmath>
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
    std::array<double, 16> pose{};
    std::array<double, 2> elbow_initial{};
    double time = 0.0;
    robot.control([&](const franka::RobotState& robot_state,
                      franka::Duration period) -> franka::CartesianPose {
      time += period.toSec();
      if (time == 0.0) {
        pose = robot_state.O_T_EE;
        elbow_initial = robot_state.elbow;
      }

      std::array<double, 2> elbow = elbow_initial;  // elbow[1] is the flip sign, kept as it is
      elbow[0] += M_PI / 10.0 * (1.0 - std::cos(2.0 * M_PI / 10.0 * time));

      const franka::CartesianPose output(pose, elbow);
      if (time >= 10.0) {
        std::cout << std::endl << "Finished motion, shutting down example" << std::endl;
        return franka::MotionFinished(output);
      }
      return output;
    });
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
