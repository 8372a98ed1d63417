// Grasps an object of a given width with the Franka Hand, checks after 3 s that it is still held,
// and releases it.
#include <chrono>
#include <iostream>
#include <string>
#include <thread>

#include <franka/exception.h>
#include <franka/gripper.h>

int main(int argc, char** argv) {
  bool homing = false;
  double object_width = 0.0;  // [m]
  bool arguments_valid = argc == 4;
  if (arguments_valid) {
    const std::string homing_text = argv[2];
    arguments_valid = homing_text == "0" || homing_text == "1";
    homing = homing_text == "1";
    try {
      object_width = std::stod(argv[3]);
    } catch (const std::exception&) {
      arguments_valid = false;
    }
  }
  if (!arguments_valid) {
    std::cerr << "Usage: " << argv[0] << " <gripper-hostname> <homing> <object-width>" << std::endl
              << "homing: 0 or 1; object-width in [m]." << std::endl;
    return -1;
  }

  try {
    franka::Gripper gripper(argv[1]);
    if (homing) {
      // Homing measures the largest opening the mounted fingers allow.
      gripper.homing();
    }

    franka::GripperState gripper_state = gripper.readOnce();
    if (gripper_state.max_width < object_width) {
      std::cout << "Object is too large for the current fingers on the gripper." << std::endl;
      return -1;
    }

    constexpr double kSpeed = 0.1;   // [m/s]
    constexpr double kForce = 60.0;  // [N]
    if (!gripper.grasp(object_width, kSpeed, kForce)) {
      std::cout << "Failed to grasp object." << std::endl;
      return -1;
    }

    std::this_thread::sleep_for(std::chrono::seconds(3));
    gripper_state = gripper.readOnce();
    if (!gripper_state.is_grasped) {
      std::cout << "Object lost." << std::endl;
      return -1;
    }

    std::cout << "Grasped object, will release it now." << std::endl;
    gripper.stop();
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
