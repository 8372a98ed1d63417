#include "csp/view/inputs.hpp"

#include <filesystem>
#include <stdexcept>
#include <utility>

#include "csp/io/robot_config.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/session_log.hpp"
#include "csp/run/sources.hpp"

namespace csp::view {
ViewRobot view_robot(const rt::Scenario& scenario) {
  return {scenario.emulator.plant, load_robot_config(scenario.robot_file).name, scenario.emulator.scene,
          scenario.has_hand};
}

JointLog run_scenario(const rt::Scenario& given) {
  if (given.duration > kMaxViewedScenarioSeconds)
    throw std::invalid_argument("csp view runs a scenario of at most " + std::to_string(static_cast<int>(kMaxViewedScenarioSeconds)) +
                                " s (" + given.path + " lasts " + std::to_string(given.duration) +
                                " s): give --duration, or record it with csp emulate --log and view the log");
  rt::Scenario scenario = given;
  scenario.clock = rt::Clock::kLockstep;   // shown afterwards: no reason to wait for the wall clock
  run::Run run(scenario);
  run::JointLogRecorder recorder(run.emulator());   // from the pose it starts from
  run.observe(recorder);
  run::ControllerSource controller(run);
  run.run(controller);
  recorder.log().source = "scenario " + scenario.path;
  return std::move(recorder.log());
}

LogInput read_log_input(const std::string& log_path, const std::string& state_channel, const std::string& scenario_path) {
  LogInput input;
  input.log = run::read_joint_log(log_path, state_channel);
  if (!scenario_path.empty()) {
    input.robot = view_robot(rt::load_scenario(scenario_path));
    input.note = "the robot and scene of " + scenario_path;
    return input;
  }
  const run::SessionRobot recorded = run::session_robot(log_path, state_channel, {});
  std::error_code error;
  if (recorded.recorded && std::filesystem::is_regular_file(recorded.recorded_scenario, error)) {
    input.robot = view_robot(rt::load_scenario(recorded.recorded_scenario));
    input.note = "the log's recorded scenario " + recorded.recorded_scenario;
  } else if (recorded.recorded) {
    const RobotConfig config = load_robot_config(recorded.robot_file);
    ModelOptions options;
    options.end_effector = recorded.end_effector;
    input.robot = {model_parameters(config, options), config.name, nullptr, recorded.end_effector == "hand"};
    input.note = "the log's recorded robot file " + recorded.recorded->recorded_path + " (its scenario " +
                 recorded.recorded_scenario + " is not here: no scene; give --scenario)";
  } else {
    input.robot = view_robot(rt::load_scenario(rt::default_scenario_path()));
    input.note = "the default scenario's robot, no scene (give --scenario for the robot and scene the log ran)";
  }
  return input;
}

}  // namespace csp::view
