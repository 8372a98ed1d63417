// csp_lcm_joint_impedance: joint impedance tracking of a smooth excitation in its own process,
// driving `csp serve` over LCM (docs/bridge.md). Gains of libfranka's joint_impedance_control.
#include "csp/bridge/controllers.hpp"
#include "example_main.hpp"

int main(int argc, char** argv) {
  double amplitude = 0.2;
  return csp::bridge::run_example_controller(
      argc, argv, "csp_lcm_joint_impedance",
      "Track a joint excitation with a joint impedance controller (torque mode) through csp serve",
      [&](CLI::App& app) {
        app.add_option("--amplitude", amplitude, "Excitation amplitude on every joint [rad]")->check(CLI::NonNegativeNumber);
      },
      [&](double duration) {
        return csp::bridge::joint_impedance_controller(csp::bridge::example_joint_stiffness(), csp::bridge::example_joint_damping(),
                                                       csp::bridge::example_excitation(amplitude), duration);
      });
}
