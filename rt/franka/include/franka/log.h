// libfranka 0.9's home of franka::Record and logToCSV (0.15 moved them to
// franka/logging/robot_state_log.hpp); kept so that 0.9 programs build unchanged.
#pragma once

#include "franka/logging/robot_state_log.hpp"
