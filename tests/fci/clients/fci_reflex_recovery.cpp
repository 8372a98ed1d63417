// fci_reflex_recovery ROBOT_ADDRESS jump|recover: a reflex as a Franka user meets it.
//   jump:    a joint position motion whose command jumps by kJump rad in one cycle: the robot's
//            reflex ends it and libfranka throws franka::ControlException; then as `recover`.
//   recover: automaticErrorRecovery, then a short motion that must succeed.
// Prints one JSON object a line (tests/fci/run_client.py reads them): {"state": ...} as read at the
// start, {"exception": what} for the jump's exception, {"state_after_reflex": ...},
// {"recovered": true}, {"second_motion": "finished"}; a libfranka error anywhere else ends it as
// {"error": what} with exit 1.
#include <iostream>
#include <string>

#include <franka/exception.h>
#include <franka/robot.h>

#include "client_output.hpp"

namespace {

constexpr double kJump = 0.1;              // [rad] in one millisecond: 100 rad/s
constexpr double kSecondMotionSeconds = 0.2;

using csp_fci_clients::json_state;
using csp_fci_clients::json_string;

// Holds the pose it starts at for kSecondMotionSeconds.
void hold_still(franka::Robot& robot) {
  std::array<double, 7> q_start{};
  double time = 0.0;
  robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::JointPositions {
    time += period.toSec();
    if (time == 0.0) q_start = state.q_d;
    if (time >= kSecondMotionSeconds) return franka::MotionFinished(franka::JointPositions(q_start));
    return q_start;
  });
}

// Holds still for 10 cycles, then commands joint 1 kJump further: libfranka's rate limiter and
// low-pass filter are off (limit_rate false, kMaxCutoffFrequency), so the jump reaches the robot.
void jump(franka::Robot& robot) {
  std::array<double, 7> q_start{};
  int cycle = 0;
  robot.control(
      [&](const franka::RobotState& state, franka::Duration) -> franka::JointPositions {
        if (cycle == 0) q_start = state.q_d;
        franka::JointPositions command = q_start;
        if (++cycle > 10) command.q[0] += kJump;
        return command;
      },
      franka::ControllerMode::kJointImpedance, false, franka::kMaxCutoffFrequency);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc == 3 ? argv[2] : "";
  if (mode != "jump" && mode != "recover") {
    std::cerr << "usage: " << argv[0] << " ROBOT_ADDRESS jump|recover\n";
    return 2;
  }
  try {
    // kIgnore: no real-time scheduling asked for (the tests run the robot on the lockstep clock).
    franka::Robot robot(argv[1], franka::RealtimeConfig::kIgnore);
    std::cout << "{\"state\":" << json_state(robot.readOnce()) << "}" << std::endl;
    if (mode == "jump") {
      try {
        jump(robot);
        std::cout << "{\"exception\":null}" << std::endl;
      } catch (const franka::ControlException& e) {
        std::cout << "{\"exception\":" << json_string(e.what()) << "}" << std::endl;
      }
      std::cout << "{\"state_after_reflex\":" << json_state(robot.readOnce()) << "}" << std::endl;
    }
    robot.automaticErrorRecovery();
    std::cout << "{\"recovered\":true}" << std::endl;
    hold_still(robot);
    std::cout << "{\"second_motion\":\"finished\"}" << std::endl;
  } catch (const franka::Exception& e) {
    std::cout << "{\"error\":" << json_string(e.what()) << "}" << std::endl;
    return 1;
  }
  return 0;
}
