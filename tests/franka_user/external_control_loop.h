// The external control loop of libfranka 0.15 (franka/active_control.h), shared by the
// *_external_control_loop examples: the program, not Robot::control, runs the 1 kHz loop.
#pragma once

#include <franka/active_control_base.h>

// Each cycle reads the robot state and the time since the last state with readOnce, computes the
// command with motion(state, period) and sends it with writeOnce, until a command says
// motion_finished. A command the robot refuses ends the loop with the robot's ControlException.
template <typename Motion>
void runExternalControlLoop(franka::ActiveControlBase& active_control, Motion motion) {
  bool motion_finished = false;
  while (!motion_finished) {
    const auto [robot_state, period] = active_control.readOnce();
    const auto command = motion(robot_state, period);
    motion_finished = command.motion_finished;
    active_control.writeOnce(command);
  }
}
