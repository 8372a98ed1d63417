// csp plan: trajectories for a medical task's scene (docs/planning.md). `check` judges any
// trajectory file against a scene and the robot's limits; the planning subcommands write the
// plan's files (planners/plan_files.hpp), check them independently and report (planners/report.hpp);
// --verify runs the written scenario on the emulator (rt: apps may use it, planners may not).
//
// Exit codes: 0 a valid plan (or a passing check), 1 no valid plan or a failing check (the report
// says why, with the best attempt), 2 bad input (one message naming what and where).
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "csp/dynamics/algorithms.hpp"
#include "csp/io/yaml_field.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/plan_files.hpp"
#include "csp/planners/report.hpp"
#include "csp/rt/controllers.hpp"

namespace csp::cli {
namespace {

namespace fs = std::filesystem;
using planners::PlanReport;
using planners::PlanRequest;
using planners::Scene;

// A shipped robot (panda, fr3) or a robot file.
std::string robot_file(const std::string& robot) {
  if (robot == "panda" || robot == "fr3") return rt::shipped_config_dir() + "/robots/" + robot + ".yaml";
  if (!fs::is_regular_file(robot))
    throw UsageError("--robot: expected panda, fr3 or a robot file (`" + robot + "` is not a readable file)");
  return robot;
}

// A shipped scene by name (configs/scenes/NAME.yaml) or a scene file.
std::string scene_file(const std::string& scene) {
  const std::string shipped = rt::shipped_config_dir() + "/scenes/" + scene + ".yaml";
  if (scene.find('/') == std::string::npos && scene.find('.') == std::string::npos && fs::is_regular_file(shipped))
    return shipped;
  if (!fs::is_regular_file(scene))
    throw UsageError("--scene: expected a scene file or the name of a shipped scene (configs/scenes/), got `" + scene +
                     "`");
  return scene;
}

// The robot with the scene's tool as its end effector (mass and TCP): what the plan is made for.
Model scene_model(const std::string& robot, const Scene& scene) {
  return Model(planners::with_tool(model_parameters(load_robot_config(robot), {}), scene.tool));
}

std::string robot_name(const std::string& robot) { return fs::path(robot).stem().string(); }

// --- check -----------------------------------------------------------------------------------------

struct CheckArguments {
  std::string trajectory, scene, robot = "panda", out;
  double power_limit = planners::CheckOptions{}.power_limit;
  double tool_speed = 0.0;
};

int run_check(const CheckArguments& args) {
  const Scene scene = planners::load_scene(scene_file(args.scene));
  const std::string robot = robot_file(args.robot);
  const Model model = scene_model(robot, scene);
  if (!(args.power_limit > 0.0)) throw UsageError("--power-limit: expected a positive power [W]");
  if (args.tool_speed < 0.0) throw UsageError("--tool-speed: expected a speed >= 0 [m/s] (0: the robot file's)");
  const JointLog log = read_joint_log_csv(args.trajectory);
  planners::CheckOptions options;
  options.power_limit = args.power_limit;
  options.tool_speed_limit = args.tool_speed;
  PlanReport report;
  report.title = "csp plan check " + fs::path(args.trajectory).filename().string();
  report.command_line = "csp plan check " + args.trajectory + " --scene " + args.scene + " --robot " + args.robot;
  report.scene_name = scene.name;
  report.robot_name = robot_name(robot);
  report.check = planners::check_trajectory(log, model, scene, options);
  if (!args.out.empty()) planners::write_report(args.out, report, scene);
  std::cout << planners::to_json(report).dump(2) << '\n';
  return report.passed() ? 0 : 1;
}

// --- rebuild -----------------------------------------------------------------------------------

struct RebuildArguments {
  std::string plan, out;
};

}  // namespace

Command add_plan_command(CLI::App& app) {
  CLI::App* plan = app.add_subcommand(
      "plan", "Trajectories for a medical task's scene: excitations, transfers, task paths, and the check of any "
              "trajectory against a scene and the limits (docs/planning.md)");
  plan->require_subcommand(1);

  auto check = std::make_shared<CheckArguments>();
  CLI::App* check_command = plan->add_subcommand(
      "check", "Check a trajectory (joint log, 1 kHz) against a scene and the robot's limits: exit 0 passed, 1 failed "
               "(the failures listed), 2 bad input");
  check_command->add_option("trajectory", check->trajectory, "Trajectory file (joint log CSV, docs/joint-log.md)")
      ->required();
  check_command->add_option("--scene", check->scene, "Scene file, or a shipped scene's name (configs/scenes/)")
      ->required();
  check_command->add_option("--robot", check->robot, "panda, fr3 or a robot file")->capture_default_str();
  check_command->add_option("--power-limit", check->power_limit, "Power limit [W] (the emulator's)")
      ->capture_default_str();
  check_command->add_option("--tool-speed", check->tool_speed,
                            "TCP speed limit [m/s] (default: the robot file's Cartesian translation limit)");
  check_command->add_option("--out", check->out, "Also write report.json, report.md and the figures here");

  return [=] {
    if (check_command->parsed()) return run_check(*check);
    return 2;
  };
}

}  // namespace csp::cli
