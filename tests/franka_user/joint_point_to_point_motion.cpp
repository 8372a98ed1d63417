// Moves the robot to the joint configuration given on the command line with MotionGenerator.
//
// Warning: the robot moves; make sure there is enough space around it.
#include <array>
#include <cmath>
#include <iostream>
#include <string>

#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"

namespace {
// The whole argument as a finite number, or false.
bool parseNumber(const char* text, double* value) {
  try {
    size_t used = 0;
    *value = std::stod(text, &used);
    return used == std::string(text).size() && std::isfinite(*value);
  } catch (const std::exception&) {
    return false;
  }
}
}  // namespace

int main(int argc, char** argv) {
  std::array<double, 7> q_goal{};
  double speed_factor = 0.0;
  bool arguments_valid = argc == 10;
  for (int i = 0; arguments_valid && i < 7; ++i) {
    arguments_valid = parseNumber(argv[i + 2], &q_goal[static_cast<size_t>(i)]);
  }
  arguments_valid = arguments_valid && parseNumber(argv[9], &speed_factor) && speed_factor > 0.0 &&
                    speed_factor <= 1.0;
  if (!arguments_valid) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname> "
              << "<joint0> <joint1> <joint2> <joint3> <joint4> <joint5> <joint6> "
              << "<speed-factor>" << std::endl
              << "joint0 to joint6 are joint angles in [rad]." << std::endl
              << "speed-factor must be between zero and one." << std::endl;
    return -1;
  }

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);

    MotionGenerator motion_generator(speed_factor, q_goal);
    std::cout << "WARNING: This example will move the robot! "
              << "Please make sure to have the user stop button at hand!" << std::endl
              << "Press Enter to continue..." << std::endl;
    std::cin.ignore();
    robot.control(motion_generator);
    std::cout << "Motion finished" << std::endl;
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
