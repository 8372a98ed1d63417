#include "csp/can/cia402.hpp"

namespace csp::can {

const char* drive_state_name(DriveState state) {
  switch (state) {
    case DriveState::kNotReadyToSwitchOn: return "not ready to switch on";
    case DriveState::kSwitchOnDisabled: return "switch on disabled";
    case DriveState::kReadyToSwitchOn: return "ready to switch on";
    case DriveState::kSwitchedOn: return "switched on";
    case DriveState::kOperationEnabled: return "operation enabled";
    case DriveState::kQuickStopActive: return "quick stop active";
    case DriveState::kFaultReactionActive: return "fault reaction active";
    case DriveState::kFault: return "fault";
  }
  return "?";
}

uint16_t statusword_state_bits(DriveState state) {
  switch (state) {
    case DriveState::kNotReadyToSwitchOn: return 0x00;
    case DriveState::kSwitchOnDisabled: return 0x40;
    case DriveState::kReadyToSwitchOn: return 0x31;
    case DriveState::kSwitchedOn: return 0x33;
    case DriveState::kOperationEnabled: return 0x37;
    case DriveState::kQuickStopActive: return 0x17;
    case DriveState::kFaultReactionActive: return 0x1F;
    case DriveState::kFault: return 0x08;
  }
  return 0;
}

namespace {
// Device control commands (CiA 402 controlword bits 0-3 and 7; x = any).
bool disable_voltage(uint16_t cw) { return (cw & 0x82) == 0x00; }   // 0xxx xx0x
bool quick_stop(uint16_t cw) { return (cw & 0x86) == 0x02; }        // 0xxx x01x
bool shutdown(uint16_t cw) { return (cw & 0x87) == 0x06; }          // 0xxx x110
bool switch_on(uint16_t cw) { return (cw & 0x87) == 0x07; }         // 0xxx x111 (also 0x0F)
bool disable_operation(uint16_t cw) { return (cw & 0x8F) == 0x07; } // 0xxx 0111
bool enable_operation(uint16_t cw) { return (cw & 0x8F) == 0x0F; }  // 0xxx 1111
}  // namespace

DriveState next_state(DriveState state, uint16_t cw, uint16_t previous, int quick_stop_option) {
  using S = DriveState;
  switch (state) {
    case S::kNotReadyToSwitchOn: return S::kSwitchOnDisabled;   // 1: self-test done
    case S::kSwitchOnDisabled: return shutdown(cw) ? S::kReadyToSwitchOn : state;   // 2
    case S::kReadyToSwitchOn:
      if (disable_voltage(cw) || quick_stop(cw)) return S::kSwitchOnDisabled;       // 7
      return switch_on(cw) ? S::kSwitchedOn : state;                                 // 3
    case S::kSwitchedOn:
      if (disable_voltage(cw) || quick_stop(cw)) return S::kSwitchOnDisabled;       // 10
      if (shutdown(cw)) return S::kReadyToSwitchOn;                                  // 6
      return enable_operation(cw) ? S::kOperationEnabled : state;                   // 4
    case S::kOperationEnabled:
      if (disable_voltage(cw)) return S::kSwitchOnDisabled;                          // 9
      if (quick_stop(cw)) return S::kQuickStopActive;                                // 11
      if (shutdown(cw)) return S::kReadyToSwitchOn;                                  // 8
      return disable_operation(cw) ? S::kSwitchedOn : state;                        // 5
    case S::kQuickStopActive:
      if (disable_voltage(cw)) return S::kSwitchOnDisabled;                                   // 12
      return quick_stop_option >= 5 && enable_operation(cw) ? S::kOperationEnabled : state;   // 16
    case S::kFaultReactionActive: return state;   // 14 happens when the reaction is over (the bus's SYNC)
    case S::kFault:
      return (cw & 0x80) && !(previous & 0x80) ? S::kSwitchOnDisabled : state;      // 15: bit 7 rising edge
  }
  return state;
}

}  // namespace csp::can
