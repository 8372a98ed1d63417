// franka::Record: one cycle of the log a ControlException carries.
#pragma once

#include <array>

#include "franka/robot_state.h"

namespace franka {

// libfranka's Record holds the state and the full robot command; CSP's holds the state and the
// seven values the controller sent in that cycle (torques, positions or velocities).
struct Record {
  RobotState state;
  std::array<double, 7> command{};
  bool command_received = false;   // false: lost on the way, or not sent
};

}  // namespace franka
