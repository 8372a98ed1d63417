// The CiA 402 drive state machine ("power drive system" states), as pure functions of the
// controlword: what a 402 master walks with 0x06 / 0x07 / 0x0F and a rising bit 7.
#pragma once

#include <cstdint>

namespace csp::can {

enum class DriveState {
  kNotReadyToSwitchOn,
  kSwitchOnDisabled,
  kReadyToSwitchOn,
  kSwitchedOn,
  kOperationEnabled,
  kQuickStopActive,
  kFaultReactionActive,
  kFault,
};
const char* drive_state_name(DriveState state);

// The state's statusword bits 0-6 (CiA 402: under mask 0x6F, 0x21 ready to switch on, 0x23
// switched on, 0x27 operation enabled, 0x07 quick stop active; under mask 0x4F, 0x40 switch on
// disabled, 0x0F fault reaction active, 0x08 fault). Bit 4 (voltage enabled) is set while powered.
uint16_t statusword_state_bits(DriveState state);

// The state after the controlword `controlword` arrives (the previous one for bit 7's rising edge).
// quick_stop_option is 0x605A: 5-8 stay in quick stop active, where enable operation resumes;
// 0-4 leave it for switch on disabled once the stop is over (quick_stop_over). Faults enter
// through fault(), not through the controlword.
DriveState next_state(DriveState state, uint16_t controlword, uint16_t previous_controlword, int quick_stop_option);

// Transition 12 without a command: the stop is over and 0x605A is 0-4.
inline DriveState quick_stop_over(DriveState state, int quick_stop_option) {
  return state == DriveState::kQuickStopActive && quick_stop_option <= 4 ? DriveState::kSwitchOnDisabled : state;
}

// Transition 13: any state but fault -> fault reaction active.
inline DriveState fault(DriveState state) {
  return state == DriveState::kFault ? state : DriveState::kFaultReactionActive;
}

}  // namespace csp::can
