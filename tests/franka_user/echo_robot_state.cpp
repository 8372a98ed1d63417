// Reads the robot state continuously with Robot::read and prints 100 states.
#include <iostream>

#include <franka/exception.h>
#include <franka/robot.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  try {
    franka::Robot robot(argv[1]);

    int printed = 0;
    robot.read([&printed](const franka::RobotState& robot_state) {
      // Printing takes time; acceptable in a read loop, never in a control loop.
      std::cout << robot_state << std::endl;
      return ++printed < 100;
    });
    std::cout << "Done." << std::endl;
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
