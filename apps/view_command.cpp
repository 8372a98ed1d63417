// csp view: a recorded run (a CSV, LCM or MCAP log, a plan's trajectory) or a scenario (run here
// first) in a browser: the arm in 3D with the scene, forces, paths and clearance, a timeline and
// plots (docs/view.md). Serves the page on 127.0.0.1 until Ctrl-C.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "csp/view/inputs.hpp"
#include "csp/view/server.hpp"
#include "view_option.hpp"

namespace csp::cli {
namespace {

struct ViewArguments {
  std::string input;
  std::string scenario;
  std::string channel = "CSP_STATE";
  std::optional<double> duration;
  int port = 8080;
};

// A scenario is a .yaml file or a shipped scenario's name (scenario_path); everything else is a log.
bool is_scenario(const std::string& input) {
  const std::string extension = std::filesystem::path(scenario_path(input)).extension().string();
  return extension == ".yaml" || extension == ".yml";
}

int run_view(const ViewArguments& args) {
  view::LogInput input;
  if (is_scenario(args.input)) {
    if (!args.scenario.empty()) throw UsageError("--scenario: only for a log (" + args.input + " is a scenario)");
    ScenarioArguments scenario_arguments;
    scenario_arguments.scenario = args.input;
    scenario_arguments.duration = args.duration;
    const rt::Scenario scenario = scenario_arguments.load();
    std::printf("csp view: running %s (%.3f s, lockstep)\n", scenario.path.c_str(), scenario.duration);
    input = {view::run_scenario(scenario), view::view_robot(scenario), "the scenario's robot and scene"};
  } else {
    if (args.duration) throw UsageError("--duration: only for a scenario (" + args.input + " is a log)");
    input = view::read_log_input(args.input, args.channel, args.scenario.empty() ? "" : scenario_path(args.scenario));
  }
  view::ViewModel model(input.robot);
  auto recording = std::make_shared<view::Recording>(view::record(model, input.log));
  nlohmann::json description = model.description();
  description["title"] = "csp view: " + args.input;
  description["live"] = false;
  view::ViewServer server("127.0.0.1", args.port, description);
  server.set_recording(recording);
  std::printf("csp view: %s: %zu rows, %.3f s, %zu events; %s\n", args.input.c_str(), input.log.size(),
              input.log.t.back() - input.log.t.front(), recording->events.size(), input.note.c_str());
  std::printf("  view: %s (Ctrl-C ends)\n", server.url().c_str());
  std::fflush(stdout);
  wait_for_signal();
  return 0;
}

}  // namespace

Command add_view_command(CLI::App& app) {
  auto args = std::make_shared<ViewArguments>();
  CLI::App* cmd = app.add_subcommand("view", "Show a log or a scenario's run in a browser: the arm in 3D, forces, plots");
  cmd->add_option("input", args->input, "A joint log (CSV, LCM or MCAP), a plan's trajectory, or a scenario (file or shipped name)")
      ->required();
  cmd->add_option("--scenario", args->scenario, "For a log: the scenario it ran (its robot and scene; an LCM log's recorded one by default)");
  cmd->add_option("--channel", args->channel, "For an LCM log: the robot states' channel")->capture_default_str();
  cmd->add_option("--duration", args->duration, "For a scenario: run this long [s] instead of its duration");
  cmd->add_option("--port", args->port, "Serve the page on 127.0.0.1:PORT (0: a free port)")->capture_default_str()->check(CLI::Range(0, 65535));
  return [args] { return run_view(*args); };
}

}  // namespace csp::cli
