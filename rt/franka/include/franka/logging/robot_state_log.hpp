// franka::Record: one cycle of the log a ControlException carries (the last log_size cycles before
// it), and logToCSV to write it (libfranka 0.15's franka/logging/robot_state_log.hpp).
#pragma once

#include <string>
#include <vector>

#include "franka/control_types.h"
#include "franka/robot_state.h"

namespace franka {

// What the program sent in one cycle. Only the motion's own kind is meaningful; the others keep
// these neutral values (as in libfranka).
struct RobotCommand {
  JointPositions joint_positions{0, 0, 0, 0, 0, 0, 0};
  JointVelocities joint_velocities{0, 0, 0, 0, 0, 0, 0};
  CartesianPose cartesian_pose{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  CartesianVelocities cartesian_velocities{0, 0, 0, 0, 0, 0};
  Torques torques{0, 0, 0, 0, 0, 0, 0};
};

struct Record {
  RobotState state;
  RobotCommand command;
};

// The log as CSV: a header row, then one row per record (every state field, then the command).
std::string logToCSV(const std::vector<Record>& log);

}  // namespace franka
