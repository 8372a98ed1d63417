// csp_can_joint_impedance: a joint impedance controller in its own process, driving the arm's
// seven CiA 402 drives over CAN in cyclic synchronous torque mode (docs/can.md):
//   tau = K (q_d - q) - D dq,  q_d = q_0 + a (1 - cos(2 pi t / T)) on joints 1 and 4,
// with gains below libfranka's joint_impedance_control: over CAN the torque answers the state of
// the previous SYNC (two cycles from measurement to torque instead of the FCI's one), and the
// wrist's damping must stay well below inertia / delay. The robot adds gravity (0x2000 = 1).
// Works unchanged on vcan0 (csp can serve) or a physical interface (can0).
//   build/apps/csp can serve --iface vcan0 &
//   build/bridge/can/csp_can_joint_impedance --iface vcan0 --cycles 5000
// Without kernel CAN, on a kernel booted in qemu (docs/can.md, "Your own master without kernel CAN"):
//   bridge/can/tools/csp-can-sandbox --csp build/apps/csp -- build/bridge/can/csp_can_joint_impedance
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>

#include "csp/can/master.hpp"
#include "csp/can/object_dictionary.hpp"

int main(int argc, char** argv) {
  CLI::App app("Joint impedance control of seven CiA 402 drives over CAN (CST mode)", "csp_can_joint_impedance");
  std::string iface = "vcan0";
  int cycles = 5000;
  // 10 s: only how long a dead server takes to show; an emulated guest on a busy machine
  // stalls for far longer than a real bus ever makes a master wait (docs/can.md).
  double amplitude = 0.1, period = 4.0, timeout = 10.0;
  app.add_option("--iface", iface, "CAN interface")->capture_default_str();
  app.add_option("--cycles", cycles, "Control cycles (one SYNC each)")->check(CLI::Range(1, 100'000'000))->capture_default_str();
  app.add_option("--amplitude", amplitude, "Motion of joints 1 and 4 [rad]")->check(CLI::Range(0.0, 0.5))->capture_default_str();
  app.add_option("--period", period, "Period of the motion [s]")->check(CLI::Range(0.5, 100.0))->capture_default_str();
  app.add_option("--timeout", timeout, "How long to wait for SDO answers and TPDOs [s]")->check(CLI::Range(0.001, 60.0))->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const double K[7] = {300, 300, 300, 300, 120, 60, 20};   // [N m/rad]
  const double D[7] = {25, 25, 25, 10, 8, 5, 2};          // [N m s/rad]
  try {
    csp::can::Master master(iface, {1, 2, 3, 4, 5, 6, 7}, timeout);
    master.start();
    master.set_mode(csp::can::kModeCst);
    std::array<double, 7> tau{};
    master.enable(tau);   // zero torque while the drives switch on: the robot holds the arm
    std::array<double, 7> q0{};
    for (int j = 0; j < 7; ++j) q0[j] = master.feedback()[j].q;
    double max_error = 0.0;
    for (int k = 0; k < cycles; ++k) {
      const double t = k * 1e-3;
      const auto& state = master.cycle(0x0F, tau);
      for (int j = 0; j < 7; ++j) {
        const double offset = (j == 0 || j == 3) ? amplitude * (1.0 - std::cos(2.0 * M_PI * t / period)) : 0.0;
        const double error = q0[j] + offset - state[j].q;
        max_error = std::max(max_error, std::abs(error));
        tau[j] = K[j] * error - D[j] * state[j].dq;
      }
      if (!master.emergencies().empty()) {
        const csp::can::Emergency& e = master.emergencies().front();
        std::fprintf(stderr, "csp_can_joint_impedance: EMCY 0x%04X from node %d (libfranka error %d) after %d cycles\n", e.code, e.node,
                     e.franka_error, k);
        return 1;
      }
    }
    master.cycle(0x07, tau);   // disable operation: the motion finishes
    std::printf("csp_can_joint_impedance: %d cycles on %s, largest tracking error %.4f rad\n", cycles, iface.c_str(), max_error);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "csp_can_joint_impedance: %s\n", e.what());
    return 1;
  }
  return 0;
}
