// The built-in controllers a scenario can run (`csp emulate`), written against the robot's own
// model as a libfranka controller would use franka::Model.
#pragma once

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::rt {

struct BuiltinController {
  ControlMode mode;
  Controller controller;
};

// The controller of `spec`, starting from the emulator's current state; `faults` make it throw
// or return NaN at the given motion times.
BuiltinController make_controller(const ControllerSpec& spec, const ControllerFaults& faults, const Emulator& emulator);

}  // namespace csp::rt
