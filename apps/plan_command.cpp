// csp plan: trajectories for a medical task's scene (docs/planning.md). `check` judges any
// trajectory file against a scene and the robot's limits; the planning subcommands write the
// plan's files, check them independently and report; --verify runs the written scenario on the
// emulator. The pipeline is run/plan.hpp's: this file parses, calls and prints.
//
// Exit codes: 0 a valid plan (or a passing check), 1 no valid plan or a failing check (the report
// says why, with the best attempt), 2 bad input (one message naming what and where).
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/planners/task.hpp"
#include "csp/run/plan.hpp"

namespace csp::cli {
namespace {

namespace fs = std::filesystem;
using planners::PlanReport;
using planners::PlanRequest;

// The verdict on stderr, one line (the JSON report stays on stdout): PASSED, or FAILED with the
// first failures, so that a check's outcome reads without the report.
std::string verdict(const PlanReport& report) {
  if (report.passed())
    return format("PASSED (%zu samples, %.3f s%s)", report.check.samples, report.check.duration,
                  report.verify ? ", verified on the emulator" : "");
  std::vector<std::string> reasons = report.problems;
  for (const planners::CheckFailure& f : report.check.failures)
    reasons.push_back(f.kind + (f.joint > 0 ? " joint " + std::to_string(f.joint) : "") +
                      format(" at t = %.3f s (%g, limit %g)", f.t, f.value, f.limit) +
                      (f.detail.empty() ? "" : " " + f.detail));
  if (report.verify && !report.verify->passed())
    reasons.push_back("emulated: " + (report.verify->reflex.empty() ? std::string("contact with the scene")
                                                                    : "reflex " + report.verify->reflex.front()));
  std::string text = "FAILED: ";
  const std::size_t shown = std::min<std::size_t>(reasons.size(), 3);
  for (std::size_t k = 0; k < shown; ++k) text += (k ? "; " : "") + reasons[k];
  if (reasons.size() > shown) text += format("; and %zu more (see the report)", reasons.size() - shown);
  return text;
}

// --- check -----------------------------------------------------------------------------------------

struct CheckArguments {
  std::string trajectory, scene, robot = "panda", out;
  double power_limit = 0.0;
  double tool_speed = 0.0;
  bool progress = false;
};

// The files of a plan's report (planners::write_report) and of the plan itself (write_plan_files).
const std::vector<std::string> kReportFiles = {"report.json", "report.md", "limits.svg", "clearance.svg", "tool_path.svg",
                                               "singular_values.svg"};
const std::vector<std::string> kPlanFiles = {"trajectory.csv", "robot.yaml", "scenario.yaml", "plan.yaml",  "report.json",
                                             "report.md",      "limits.svg", "clearance.svg", "tool_path.svg", "singular_values.svg"};

int run_check(const CheckArguments& args) {
  Outputs().directory("--out", args.out, kReportFiles).input("the trajectory", args.trajectory).check();
  ProgressMeter progress("csp plan check", args.progress);
  progress.update("checking the trajectory", 0, 0);
  planners::CheckOptions options;
  options.power_limit = args.power_limit;
  options.tool_speed_limit = args.tool_speed;
  const PlanReport report = run::check_trajectory_file(args.trajectory, args.scene, args.robot, options, args.out);
  std::cout << planners::to_json(report).dump(2) << '\n';
  progress.finish(verdict(report));
  return report.passed() ? 0 : 1;
}

// --- planning: the pipeline shared by excite, transfer and task ---------------------------------

// The options every planning subcommand takes.
struct PlanArguments {
  std::string scene, robot = "panda", out;
  long long seed = 1;
  bool verify = false;
  bool progress = false;
};

// The job of a planning subcommand: the request as plan.yaml records it (the command's own options,
// as given, so that `csp plan rebuild` asks for the same plan).
run::PlanJob plan_job(const std::string& command, const PlanArguments& args, const CLI::App& subcommand,
                      ProgressMeter& progress) {
  if (args.seed < 1 || args.seed > 4294967295LL) throw UsageError("--seed: expected a whole number from 1 to 2^32-1");
  Outputs().directory("--out", args.out, kPlanFiles).check();   // before the planning (seconds to minutes)
  run::PlanJob job{{command, args.scene, args.robot, static_cast<std::uint64_t>(args.seed), {}}, args.out, args.verify,
                   progress.callback()};
  for (const CLI::Option* option : subcommand.get_options()) {
    const std::string name = option->get_lnames().empty() ? "" : option->get_lnames().front();
    if (option->count() == 0 || name.empty() || name == "help" || name == "scene" || name == "robot" ||
        name == "seed" || name == "out" || name == "progress")   // progress: how it is shown, not what is made
      continue;
    job.request.options.emplace_back(name, option->get_expected_min() == 0 ? "" : option->as<std::string>());
  }
  return job;
}

// Prints the report (JSON on stdout, the verdict on stderr); exit 0 for a valid plan, 1 otherwise.
int print_plan(const run::PlanJob& job, const run::PlanOutcome& outcome, ProgressMeter& progress) {
  std::cout << planners::to_json(outcome.report).dump(2) << '\n';
  if (outcome.status == planners::PlannerStatus::kNoSolution)
    progress.finish("FAILED: no plan: " + outcome.report.problems.front() + " (best attempt in " +
                    (fs::path(job.out) / "report.json").string() + ")");
  else progress.finish(verdict(outcome.report) + ", files in " + job.out);
  return outcome.passed() ? 0 : 1;
}

// --- transfer ---

struct TransferArguments {
  PlanArguments plan;
  std::string from, to;
  std::string planner = "rrtconnect";
  long max_iterations = planners::TransferOptions{}.max_iterations;
};

int run_transfer(const TransferArguments& args, const CLI::App& command) {
  ProgressMeter progress("csp plan transfer", args.plan.progress);
  const run::PlanJob job = plan_job("transfer", args.plan, command, progress);
  planners::TransferOptions options;
  options.planner = args.planner;
  options.max_iterations = args.max_iterations;
  return print_plan(job, run::plan_transfer(job, args.from, args.to, options), progress);
}

// --- task ---

struct TaskArguments {
  PlanArguments plan;
  int max_iterations = planners::TaskPathOptions{}.max_iterations;
};

int run_task(const TaskArguments& args, const CLI::App& command) {
  ProgressMeter progress("csp plan task", args.plan.progress);
  const run::PlanJob job = plan_job("task", args.plan, command, progress);
  return print_plan(job, run::plan_task(job, args.max_iterations), progress);
}

// --- excite ---

struct ExciteArguments {
  PlanArguments plan;
  int harmonics = planners::ExcitationOptions{}.harmonics;
  double fundamental_hz = planners::ExcitationOptions{}.fundamental_hz;
  int periods = planners::ExcitationOptions{}.periods;
  int anchors = 1;
  std::string placement = "hover";
  std::string criterion = "task";
  int max_evaluations = planners::ExcitationOptions{}.max_evaluations;
  long transfer_iterations = planners::TransferOptions{}.max_iterations;
};

int run_excite(const ExciteArguments& args, const CLI::App& command) {
  ProgressMeter progress("csp plan excite", args.plan.progress);
  const run::PlanJob job = plan_job("excite", args.plan, command, progress);
  run::ExcitationJob excitation;
  excitation.anchors = args.anchors;
  excitation.placement = args.placement;
  excitation.criterion = args.criterion;
  excitation.options.harmonics = args.harmonics;
  excitation.options.fundamental_hz = args.fundamental_hz;
  excitation.options.periods = args.periods;
  excitation.options.max_evaluations = args.max_evaluations;
  excitation.transfer_iterations = args.transfer_iterations;
  return print_plan(job, run::plan_excitation(job, excitation), progress);
}

// --- rebuild -----------------------------------------------------------------------------------

void add_plan_options(CLI::App& command, PlanArguments& args) {
  command.add_option("--scene", args.scene, "Scene file, or a shipped scene's name (configs/scenes/)")->required();
  command.add_option("--robot", args.robot, "panda, fr3 or a robot file")->capture_default_str();
  command.add_option("--seed", args.seed, "Seed of the planners (1 .. 2^32-1): the same seed, the same files")
      ->capture_default_str();
  command.add_option("--out", args.out, "Directory of the plan's files")->required();
  command.add_flag("--verify", args.verify, "Run the written scenario on the emulator and report it");
  add_progress_flag(command, args.progress);
}

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
  check_command->add_option("--power-limit", check->power_limit,
                            "Power limit [W] (default: the robot file's, as the emulator's; 80 W unless it gives one)");
  check_command->add_option("--tool-speed", check->tool_speed,
                            "TCP speed limit [m/s] (default: the robot file's Cartesian translation limit)");
  check_command->add_option("--out", check->out, "Also write report.json, report.md and the figures here");
  add_progress_flag(*check_command, check->progress);

  auto transfer = std::make_shared<TransferArguments>();
  CLI::App* transfer_command =
      plan->add_subcommand("transfer", "A collision-free transfer between two named poses of the scene (OMPL), timed");
  add_plan_options(*transfer_command, transfer->plan);
  transfer_command->add_option("--from", transfer->from, "Named pose to start from")->required();
  transfer_command->add_option("--to", transfer->to, "Named pose to end at")->required();
  transfer_command->add_option("--planner", transfer->planner, "rrtconnect, rrtstar, bitstar or lazyprmstar")
      ->capture_default_str();
  transfer_command->add_option("--max-iterations", transfer->max_iterations, "The planner's budget (iterations)")
      ->capture_default_str();

  auto task = std::make_shared<TaskArguments>();
  CLI::App* task_command = plan->add_subcommand(
      "task", "The medical task's own path on its constraint manifold (probe on the skin, shaft through the trocar, "
              "drill on the burr axis), timed");
  add_plan_options(*task_command, task->plan);
  task_command->add_option("--max-iterations", task->max_iterations, "The planner's budget (iterations)")
      ->capture_default_str();

  auto excite = std::make_shared<ExciteArguments>();
  CLI::App* excite_command = plan->add_subcommand(
      "excite", "An excitation trajectory for identification, weighted toward the task, with the transfers to its "
                "anchors and back (docs/excitation.md)");
  add_plan_options(*excite_command, excite->plan);
  excite_command->add_option("--harmonics", excite->harmonics, "Harmonics of the Fourier series")->capture_default_str();
  excite_command->add_option("--fundamental-hz", excite->fundamental_hz, "Fundamental frequency [Hz]")
      ->capture_default_str();
  excite_command->add_option("--periods", excite->periods, "Periods per anchor")->capture_default_str();
  excite_command->add_option("--anchors", excite->anchors, "Excitation anchors (hover: at most the task's 2)")
      ->capture_default_str();
  excite_command->add_option("--anchor-placement", excite->placement,
                             "hover (the task's hover poses) or medoids (k-medoids of the task path's states, "
                             "retracted off the patient)")
      ->capture_default_str();
  excite_command->add_option("--criterion", excite->criterion, "task (weighted toward the task), d (D-optimal) or cond (condition number)")
      ->capture_default_str();
  excite_command->add_option("--max-evaluations", excite->max_evaluations, "The optimiser's budget per anchor")
      ->capture_default_str();
  excite_command->add_option("--transfer-iterations", excite->transfer_iterations, "The transfers' planner budget")
      ->capture_default_str();

  auto rebuild = std::make_shared<std::pair<std::string, std::string>>();
  CLI::App* rebuild_command = plan->add_subcommand(
      "rebuild", "Make a plan again from its plan.yaml: the same files, byte for byte");
  rebuild_command->add_option("plan", rebuild->first, "A plan's plan.yaml")->required();
  rebuild_command->add_option("--out", rebuild->second, "Directory of the files (default: the plan.yaml's)");
  auto rebuild_progress = std::make_shared<bool>(false);
  add_progress_flag(*rebuild_command, *rebuild_progress);

  return [=]() -> int {
    if (check_command->parsed()) return run_check(*check);
    if (transfer_command->parsed()) return run_transfer(*transfer, *transfer_command);
    if (task_command->parsed()) return run_task(*task, *task_command);
    if (excite_command->parsed()) return run_excite(*excite, *excite_command);
    // rebuild: the recorded request parsed again as the command line it was.
    const PlanRequest request = planners::read_plan_request(rebuild->first);
    const std::string out =
        rebuild->second.empty() ? fs::path(rebuild->first).parent_path().string() : rebuild->second;
    std::vector<std::string> args = {"plan", request.command, "--scene", request.scene, "--robot", request.robot,
                                     "--seed", std::to_string(request.seed), "--out", out.empty() ? "." : out};
    for (const auto& [name, value] : request.options) {
      args.push_back("--" + name);
      if (!value.empty()) args.push_back(value);
    }
    if (*rebuild_progress) args.push_back("--progress");
    CLI::App again;
    const Command run = add_plan_command(again);
    std::reverse(args.begin(), args.end());   // CLI11 takes the arguments last first
    again.parse(args);
    return run();
  };
}

}  // namespace csp::cli
