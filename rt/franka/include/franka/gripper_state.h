// franka::GripperState: the Franka Hand's state, with libfranka's fields.
#pragma once

#include <cstdint>
#include <ostream>

#include "franka/duration.h"

namespace franka {

struct GripperState {
  // Opening width between the fingers [m].
  double width{};
  // Widest opening, measured by Gripper::homing (0 until the hand has been homed) [m].
  double max_width{};
  // True while a successful grasp holds its object within the grasp's tolerance band.
  bool is_grasped{};
  // The hand's temperature [degC].
  uint16_t temperature{};
  // As libfranka fills it: the number of the hand's state message (strictly increasing).
  Duration time{};
};

// The state as a JSON object: {"width": ..., "max_width": ..., ...}.
std::ostream& operator<<(std::ostream& ostream, const franka::GripperState& gripper_state);

}  // namespace franka
