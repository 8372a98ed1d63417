// csp_lcm_float: a gravity-compensated float controller in its own process, driving `csp serve`
// over LCM (docs/bridge.md).
#include "csp/bridge/controllers.hpp"
#include "example_main.hpp"

int main(int argc, char** argv) {
  double damping = 2.0;
  return csp::bridge::run_example_controller(
      argc, argv, "csp_lcm_float", "Float the emulated robot (torque mode, tau = -D dq) through csp serve",
      [&](CLI::App& app) {
        app.add_option("--damping", damping, "Joint damping D [N m s/rad], all joints")->check(CLI::NonNegativeNumber);
      },
      [&](double duration) { return csp::bridge::float_controller(csp::Vector7::Constant(damping), duration); });
}
