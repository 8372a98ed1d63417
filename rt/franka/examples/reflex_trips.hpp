// Purpose-built controllers that each trip one of the robot's reflexes, plausibly and with no
// other error: the reflexes example runs them, the tests check them (tests/test_franka_api.cpp).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <franka/robot.h>

#include "csp/rt/errors.hpp"
#include "csp/rt/scenario.hpp"

namespace csp_examples {

struct ReflexTrip {
  csp::rt::Error error;                             // the one error it trips
  std::string how;                                  // what the controller (or the scenario) does
  std::function<void(csp::rt::Scenario&)> prepare;  // changes to the scenario, e.g. a push; may be empty
  std::function<void(franka::Robot&)> run;          // robot.control(...) with the tripping controller
};

// Every reflex trip, in libfranka's error order.
std::vector<ReflexTrip> reflex_trips();

// A torque controller that holds the start pose and after 0.1 s returns NaN for joint 1.
std::function<franka::Torques(const franka::RobotState&, franka::Duration)> nan_controller();

// Reads states until the arm has stopped and any scripted push is over: when a reflex may be
// cleared and a new motion started.
void wait_until_settled(franka::Robot& robot);

}  // namespace csp_examples
