// Prints the size and alignment of the franka types a program holds by value, as this program's
// compiler flags lay them out. Run it built with different flags (e.g. with and without
// -march=native): a library whose ABI does not depend on the user's flags prints the same lines.
#include <iostream>

#include <franka/errors.h>
#include <franka/gripper.h>
#include <franka/model.h>
#include <franka/robot.h>
#include <franka/robot_state.h>

namespace {
template <typename T>
void print(const char* name) {
  std::cout << name << " sizeof " << sizeof(T) << " alignof " << alignof(T) << std::endl;
}
}  // namespace

int main() {
  print<franka::Robot>("franka::Robot");
  print<franka::Model>("franka::Model");
  print<franka::RobotState>("franka::RobotState");
  print<franka::Errors>("franka::Errors");
  print<franka::Gripper>("franka::Gripper");
  return 0;
}
