// Joint impedance trajectory tracking: joints 4 and 6 follow a sinusoid around the start pose
// with the stiffness and damping of libfranka's joint_impedance_control example, plus the
// Coriolis torques of the robot's model. Prints the RMS tracking error.
//
// usage: csp_example_joint_impedance <robot-hostname or scenario.yaml>
// (a hostname or IP address runs on $CSP_SCENARIO or configs/scenarios/libfranka_panda.yaml)
#include <cmath>
#include <iostream>

#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname or scenario.yaml>" << std::endl;
    return -1;
  }
  const std::string scenario = argv[1];
  try {
    franka::Robot robot(scenario);
    franka::Model model = robot.loadModel();
    const std::array<double, 7> k_gains{{600.0, 600.0, 600.0, 600.0, 250.0, 150.0, 50.0}};   // [N m/rad]
    const std::array<double, 7> d_gains{{50.0, 50.0, 50.0, 20.0, 20.0, 20.0, 10.0}};         // [N m s/rad]
    const double amplitude = 0.3, frequency = 0.5, duration = 4.0;   // [rad], [Hz], [s]

    std::array<double, 7> q_start{};
    double time = 0.0, squared_error = 0.0;
    std::size_t samples = 0;
    robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::Torques {
      if (period.toMSec() == 0) q_start = state.q;
      time += period.toSec();
      // q_d = q_start + A (1 - cos(w t)) on joints 4 and 6: starts at rest.
      const double w = 2.0 * M_PI * frequency;
      std::array<double, 7> q_d = q_start, dq_d{};
      for (std::size_t joint : {3, 5}) {
        q_d[joint] += amplitude * (1.0 - std::cos(w * time));
        dq_d[joint] = amplitude * w * std::sin(w * time);
      }
      const std::array<double, 7> coriolis = model.coriolis(state);
      std::array<double, 7> tau{};
      for (std::size_t i = 0; i < 7; ++i) {
        tau[i] = k_gains[i] * (q_d[i] - state.q[i]) + d_gains[i] * (dq_d[i] - state.dq[i]) + coriolis[i];
        squared_error += (q_d[i] - state.q[i]) * (q_d[i] - state.q[i]);
      }
      ++samples;
      return time >= duration ? franka::MotionFinished(franka::Torques(tau)) : franka::Torques(tau);
    });
    std::cout << "RMS joint tracking error over " << duration << " s: " << std::sqrt(squared_error / (7.0 * samples))
              << " rad\n";
  } catch (const franka::Exception& e) {
    std::cerr << e.what() << '\n';
    return 1;
  }
  return 0;
}
