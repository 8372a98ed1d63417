// franka::RobotState and franka::RobotMode: CSP's robot state, field for field libfranka's.
#pragma once

#include "csp/rt/robot_state.hpp"
#include "franka/duration.h"
#include "franka/errors.h"

namespace franka {

using RobotState = csp::rt::RobotState;
using RobotMode = csp::rt::RobotMode;

}  // namespace franka
