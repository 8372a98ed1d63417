// Gravity-compensated float: the robot compensates gravity itself, so a torque controller that
// commands only a little joint damping lets the arm float. Prints how far it drifts in 2 s (the
// robot's model is not the arm: what remains is the model error).
//
// usage: csp_example_float <robot-hostname or scenario.yaml>
// (a hostname or IP address runs on $CSP_SCENARIO or configs/scenarios/libfranka_panda.yaml)
#include <algorithm>
#include <cmath>
#include <iostream>

#include <franka/exception.h>
#include <franka/robot.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname or scenario.yaml>" << std::endl;
    return -1;
  }
  const std::string scenario = argv[1];
  try {
    franka::Robot robot(scenario);
    const std::array<double, 7> damping{{5, 5, 5, 5, 2, 2, 1}};   // [N m s/rad]
    const franka::RobotState start = robot.readOnce();
    double time = 0.0;
    franka::RobotState last;
    robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::Torques {
      time += period.toSec();
      last = state;
      std::array<double, 7> tau{};
      for (std::size_t i = 0; i < 7; ++i) tau[i] = -damping[i] * state.dq[i];
      return time >= 2.0 ? franka::MotionFinished(franka::Torques(tau)) : franka::Torques(tau);
    });
    double drift = 0.0;
    for (std::size_t i = 0; i < 7; ++i) drift = std::max(drift, std::abs(last.q[i] - start.q[i]));
    const double dx = last.O_T_EE[12] - start.O_T_EE[12], dy = last.O_T_EE[13] - start.O_T_EE[13],
                 dz = last.O_T_EE[14] - start.O_T_EE[14];
    std::cout << "after 2 s of float: largest joint drift " << drift << " rad, end effector moved "
              << std::sqrt(dx * dx + dy * dy + dz * dz) * 1000.0 << " mm\n";
  } catch (const franka::Exception& e) {
    std::cerr << e.what() << '\n';
    return 1;
  }
  return 0;
}
