// One purpose-built controller per reflex of the robot, each on a fresh robot: prints the
// ControlException each one ends in, then recovers and shows that a new motion starts.
//
// usage: csp_example_reflexes [scenario.yaml]
#include <iostream>
#include <stdexcept>

#include <franka/exception.h>
#include <franka/robot.h>

#include "csp/franka_access.hpp"
#include "csp/rt/scenario.hpp"
#include "reflex_trips.hpp"

namespace {

// A short motion that holds still and ends by itself.
void hold_briefly(franka::Robot& robot) {
  robot.control([](const franka::RobotState&, franka::Duration) {
    return franka::MotionFinished(franka::Torques({0, 0, 0, 0, 0, 0, 0}));
  });
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : csp::rt::default_scenario_path();
  try {
    csp::rt::Scenario base = csp::rt::load_scenario(path);
    base.emulator.external_wrenches.clear();   // only the pushes a trip scripts itself
    for (const csp_examples::ReflexTrip& trip : csp_examples::reflex_trips()) {
      csp::rt::Scenario scenario = base;
      if (trip.prepare) trip.prepare(scenario);
      csp::franka_access::EmulatedRobot robot(scenario);
      std::cout << csp::rt::error_name(trip.error) << ": " << trip.how << "\n  ";
      try {
        trip.run(robot);
        std::cout << "no reflex!\n";
      } catch (const franka::ControlException& e) {
        std::cout << e.what() << " (t = " << robot.readOnce().time.toSec() << " s)\n";
      }
      csp_examples::wait_until_settled(robot);
      robot.automaticErrorRecovery();
      try {
        hold_briefly(robot);
        std::cout << "  recovered, a new motion ran\n";
      } catch (const franka::ControlException& e) {
        // E.g. past a joint limit: on a real robot the arm is guided back by hand first.
        std::cout << "  recovered, but a new motion ends at once: " << e.what() << '\n';
      }
    }

    csp::franka_access::EmulatedRobot robot(base);
    std::cout << "non-finite command: a torque controller returns NaN after 0.1 s\n  ";
    try {
      robot.control(csp_examples::nan_controller());
    } catch (const std::invalid_argument& e) {   // libfranka refuses a NaN command
      std::cout << e.what() << " -> robot mode " << csp::rt::robot_mode_name(robot.readOnce().robot_mode) << '\n';
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << '\n';
    return 1;
  }
  return 0;
}
