// fci_model_query ROBOT_ADDRESS: libfranka's franka::Model of the robot at one moving state, as a
// Franka user computes it: connect, load the model (the robot's LoadModelLibrary: the library the
// robot serves is what computes), move a little, take the state in the middle of the motion
// (dq not zero: Coriolis means something) and print, on one line of JSON, that state's q and dq
// and the model's quantities there. Gravity twice: gravity(state), which takes the gravity vector
// from the state's O_ddP_O (libfranka: "hardcoded for now to {0, 0, -9.81}"), and with that
// vector given explicitly. tests/fci/run_client.py compares them with `csp model`.
#include <cmath>
#include <iostream>
#include <optional>

#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

#include "client_output.hpp"

namespace {

constexpr double kMotionSeconds = 1.0;
constexpr double kSampleSeconds = 0.25;   // the fastest moment of the motion
constexpr double kAmplitude = 0.1;        // [rad], every joint: a small move out and back

}  // namespace

int main(int argc, char** argv) {
  using csp_fci_clients::json_array;
  if (argc != 2) {
    std::cerr << "usage: " << argv[0] << " ROBOT_ADDRESS\n";
    return 2;
  }
  try {
    // kIgnore: this program asks for no real-time scheduling (run against a lockstep robot).
    franka::Robot robot(argv[1], franka::RealtimeConfig::kIgnore);
    franka::Model model = robot.loadModel();

    std::array<double, 7> q_start{};
    std::optional<franka::RobotState> sample;
    double time = 0.0;
    robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::JointPositions {
      time += period.toSec();
      if (time == 0.0) q_start = state.q_d;
      if (!sample && time >= kSampleSeconds) sample = state;
      const double offset = kAmplitude * (1.0 - std::cos(2.0 * M_PI * time / kMotionSeconds)) / 2.0;
      franka::JointPositions command = q_start;
      for (double& q : command.q) q += offset;
      if (time >= kMotionSeconds) return franka::MotionFinished(franka::JointPositions(q_start));
      return command;
    });

    if (!sample) {   // the motion ended early without an exception: nothing to report
      std::cout << "the motion ended before " << kSampleSeconds << " s\n";
      return 1;
    }
    const franka::RobotState& s = *sample;
    std::cout << "{\"q\":" << json_array(s.q) << ",\"dq\":" << json_array(s.dq)
              << ",\"F_T_EE\":" << json_array(s.F_T_EE) << ",\"m_total\":" << json_array(std::array<double, 1>{s.m_total})
              << ",\"F_x_Ctotal\":" << json_array(s.F_x_Ctotal) << ",\"I_total\":" << json_array(s.I_total)
              << ",\"mass\":" << json_array(model.mass(s)) << ",\"coriolis\":" << json_array(model.coriolis(s))
              << ",\"O_ddP_O\":" << json_array(s.O_ddP_O) << ",\"gravity\":" << json_array(model.gravity(s))
              << ",\"gravity_earth\":" << json_array(model.gravity(s, {0.0, 0.0, -9.81}))
              << ",\"pose_flange\":" << json_array(model.pose(franka::Frame::kFlange, s))
              << ",\"pose_end_effector\":" << json_array(model.pose(franka::Frame::kEndEffector, s))
              << ",\"zero_jacobian_end_effector\":" << json_array(model.zeroJacobian(franka::Frame::kEndEffector, s))
              << ",\"body_jacobian_flange\":" << json_array(model.bodyJacobian(franka::Frame::kFlange, s)) << "}\n";
  } catch (const franka::Exception& e) {
    std::cout << e.what() << '\n';
    return 1;
  }
  return 0;
}
