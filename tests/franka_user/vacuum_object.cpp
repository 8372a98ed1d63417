// Picks a part with the Cobot Pump (franka::VacuumGripper): applies vacuum, checks after 3 s that
// the vacuum still holds, and drops the part off.
#include <chrono>
#include <iostream>
#include <thread>

#include <franka/exception.h>
#include <franka/vacuum_gripper.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <vacuum-gripper-hostname>" << std::endl;
    return -1;
  }

  try {
    franka::VacuumGripper vacuum_gripper(argv[1]);
    try {
      franka::VacuumGripperState state = vacuum_gripper.readOnce();
      std::cout << "Initial vacuum gripper state: " << state << std::endl;

      // Setpoint in units of 10 mbar; false if the part is not held within the timeout.
      if (!vacuum_gripper.vacuum(100, std::chrono::milliseconds(1000))) {
        std::cout << "Failed to vacuum the object." << std::endl;
        return -1;
      }
      state = vacuum_gripper.readOnce();
      std::cout << "Vacuum gripper state after applying vacuum: " << state << std::endl;

      std::this_thread::sleep_for(std::chrono::seconds(3));
      state = vacuum_gripper.readOnce();
      if (!state.in_control_range) {
        std::cout << "Object lost." << std::endl;
        return -1;
      }

      std::cout << "Vacuumed object, will release it now." << std::endl;
      vacuum_gripper.dropOff(std::chrono::milliseconds(1000));
    } catch (const franka::Exception&) {
      vacuum_gripper.stop();  // never leave the pump running after an error
      throw;
    }
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
