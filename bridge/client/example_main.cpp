#include "example_main.hpp"

#include <cstdio>

#include "csp/bridge/client.hpp"

namespace csp::bridge {

int run_example_controller(int argc, char** argv, const char* name, const char* description,
                           const std::function<void(CLI::App&)>& add_options,
                           const std::function<rt::Controller(double duration)>& make) {
  CLI::App app{description};
  std::string url = kDefaultLcmUrl, prefix;
  double duration = 5.0, timeout = 2.0;
  app.add_option("--lcm-url", url, "LCM provider URL");
  app.add_option("--prefix", prefix, "Channel prefix of the robot");
  app.add_option("--duration", duration, "Motion time [s]")->check(CLI::PositiveNumber);
  app.add_option("--timeout", timeout, "How long to wait for a state or a reply before giving up [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  add_options(app);
  CLI11_PARSE(app, argc, argv);
  try {
    Client robot(url, prefix, timeout);
    const SessionResult result = robot.control(rt::ControlMode::kTorque, make(duration));
    std::printf("%s: %llu commands, ended at t = %.3f s in %s\n", name, static_cast<unsigned long long>(result.commands),
                result.state.time.toSec(), rt::robot_mode_name(result.state.robot_mode));
    return result.reflex ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 2;
  }
}

}  // namespace csp::bridge
