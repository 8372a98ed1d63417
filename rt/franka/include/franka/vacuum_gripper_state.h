// franka::VacuumGripperState: the Cobot Pump's state, with libfranka's fields.
#pragma once

#include <cstdint>
#include <ostream>

#include "franka/duration.h"

namespace franka {

// The pump's own health verdict.
enum class VacuumGripperDeviceStatus : uint8_t { kGreen, kYellow, kOrange, kRed };

struct VacuumGripperState {
  // The vacuum is within the setpoint's control range.
  bool in_control_range{};
  // The part left the cup after a suction cycle (dropOff).
  bool part_detached{};
  // The vacuum rose above H2 and has not fallen below H2 - h2 since.
  bool part_present{};
  VacuumGripperDeviceStatus device_status{};
  // The pump's present power [%].
  uint16_t actual_power{};
  // The system vacuum [mbar].
  uint16_t vacuum{};
  // As libfranka fills it: the number of the pump's state message (strictly increasing).
  Duration time{};
};

// The state as a JSON object: {"in_control_range": ..., ...}.
std::ostream& operator<<(std::ostream& ostream, const franka::VacuumGripperState& vacuum_gripper_state);

}  // namespace franka
