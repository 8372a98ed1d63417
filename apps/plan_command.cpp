// csp plan: trajectories for a medical task's scene (docs/planning.md). `check` judges any
// trajectory file against a scene and the robot's limits; the planning subcommands write the
// plan's files (planners/plan_files.hpp), check them independently and report (planners/report.hpp);
// --verify runs the written scenario on the emulator (rt: apps may use it, planners may not).
//
// Exit codes: 0 a valid plan (or a passing check), 1 no valid plan or a failing check (the report
// says why, with the best attempt), 2 bad input (one message naming what and where).
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/dynamics/algorithms.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/io/yaml_field.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/excitation.hpp"
#include "csp/planners/kmedoids.hpp"
#include "csp/planners/plan_files.hpp"
#include "csp/planners/profile.hpp"
#include "csp/planners/report.hpp"
#include "csp/planners/task.hpp"
#include "csp/planners/transfer.hpp"
#include "csp/rt/controllers.hpp"

namespace csp::cli {
namespace {

namespace fs = std::filesystem;
using planners::PlanReport;
using planners::PlanRequest;

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

std::string robot_name(const std::string& robot) { return fs::path(robot).stem().string(); }

// A real FR3's motors add their rotor inertia to the joints; the shipped FR3 scenario carries it
// (configs/scenarios/libfranka_fr3.yaml, with its source), and so do the plans for an FR3.
planners::Armature robot_armature(const std::string& robot) {
  if (robot_name(robot) != "fr3") return {};
  const std::string source = rt::shipped_scenario_path("libfranka_fr3");
  return {rt::load_scenario(source).emulator.plant.armature,
          "as configs/scenarios/libfranka_fr3.yaml: MuJoCo Menagerie franka_fr3 (identified in torque control)"};
}

// The robot with the scene's tool as its end effector (mass and TCP) and its motors' armature: what
// the plan is made for, and what its scenario's plant is.
Model scene_model(const std::string& robot, const Scene& scene) {
  ModelParameters parameters = with_tool(model_parameters(load_robot_config(robot), {}), scene.tool);
  parameters.armature = robot_armature(robot).values;
  return Model(parameters);
}

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
  double power_limit = planners::CheckOptions{}.power_limit;
  double tool_speed = 0.0;
  bool progress = false;
};

int run_check(const CheckArguments& args) {
  const Scene scene = load_scene(scene_file(args.scene));
  const std::string robot = robot_file(args.robot);
  const Model model = scene_model(robot, scene);
  if (!(args.power_limit > 0.0)) throw UsageError("--power-limit: expected a positive power [W]");
  if (args.tool_speed < 0.0) throw UsageError("--tool-speed: expected a speed >= 0 [m/s] (0: the robot file's)");
  const JointLog log = read_joint_log_csv(args.trajectory);
  ProgressMeter progress("csp plan check", args.progress);
  progress.update("checking the trajectory", 0, 0);
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

// What an engine made: the 1 kHz trajectory, its own record, and the scene its trajectory is checked
// against (a task's tool touches the patient by design: contact_scene).
struct Planned {
  JointLog trajectory;
  nlohmann::json made = nlohmann::json::object();
  std::vector<double> singular_values;
  std::optional<Scene> check_scene;
};

// The loaded inputs of a plan.
struct PlanContext {
  PlanRequest request;
  Scene scene;
  std::string robot_file;
  Model model;
  std::string out;
  bool verify = false;
  std::shared_ptr<ProgressMeter> progress;   // shared: the context is passed by value
};

PlanContext load_context(const std::string& command, const PlanArguments& args, const CLI::App& subcommand) {
  if (args.seed < 1 || args.seed > 4294967295LL) throw UsageError("--seed: expected a whole number from 1 to 2^32-1");
  if (args.out.empty()) throw UsageError("--out: expected the directory to write the plan into");
  PlanRequest request{command, args.scene, args.robot, static_cast<std::uint64_t>(args.seed), {}};
  // The command's own options, as given, so that `csp plan rebuild` asks for the same plan.
  for (const CLI::Option* option : subcommand.get_options()) {
    const std::string name = option->get_lnames().empty() ? "" : option->get_lnames().front();
    if (option->count() == 0 || name.empty() || name == "help" || name == "scene" || name == "robot" ||
        name == "seed" || name == "out" || name == "progress")   // progress: how it is shown, not what is made
      continue;
    request.options.emplace_back(name, option->get_expected_min() == 0 ? "" : option->as<std::string>());
  }
  Scene scene = load_scene(scene_file(args.scene));
  const std::string robot = robot_file(args.robot);
  Model model = scene_model(robot, scene);
  return {request, std::move(scene), robot, std::move(model), args.out, args.verify,
          std::make_shared<ProgressMeter>("csp plan " + command, args.progress)};
}

// --verify: the written scenario on the emulator (lockstep, as `csp emulate` runs it), the measured
// motion compared with the plan and checked against the scene.
planners::EmulatorRun verify_plan(const PlanContext& c, const Scene& scene, const JointLog& trajectory) {
  const rt::Scenario scenario = rt::load_scenario((fs::path(c.out) / "scenario.yaml").string());
  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, {}, emulator);
  planners::ClearanceChecker checker(c.model, scene);
  planners::EmulatorRun run;
  run.robot = robot_name(c.robot_file);
  for (const std::string& name : checker.classes())
    run.measured_clearance.push_back({name, std::numeric_limits<double>::infinity(), 0.0, 0.0, "", ""});
  const Vector7& tau_max = scenario.emulator.plant.joint_limits.tau_max;
  Vector7 squared = Vector7::Zero();
  long cycles = 0;
  rt::LoopOptions options;
  options.max_duration = scenario.duration;
  options.observer = [&](const rt::RobotState& state, const rt::CycleInfo&) {
    const double t = state.time.toSec();
    if (state.time.toMSec() % 100 == 0) c.progress->update("verifying on the emulator (simulated seconds)", t, scenario.duration);
    const std::size_t row = std::min(trajectory.size() - 1, static_cast<std::size_t>(std::lround(t * 1000.0)));
    const Vector7 q(state.q.data());
    const Vector7 error = (q - trajectory.q[row]).cwiseAbs();
    squared += error.cwiseAbs2();
    run.tracking_max = run.tracking_max.cwiseMax(error);
    run.peak_tau_J_fraction = run.peak_tau_J_fraction.cwiseMax(Vector7(state.tau_J.data()).cwiseAbs().cwiseQuotient(tau_max));
    const std::vector<planners::StateClearance>& by_class = checker.check_by_class(q);
    for (std::size_t k = 0; k < by_class.size(); ++k)
      if (by_class[k].clearance < run.measured_clearance[k].clearance)
        run.measured_clearance[k] = {checker.classes()[k], by_class[k].clearance, by_class[k].distance, t,
                                     std::string(by_class[k].moving), std::string(by_class[k].other)};
    ++cycles;
    run.duration = t;
  };
  const rt::MotionResult result = rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  if (cycles > 0) run.tracking_rms = (squared / static_cast<double>(cycles)).cwiseSqrt();
  if (result.reflex) {
    for (int i = 0; i < rt::kNumErrors; ++i)
      if (result.errors.flags()[i]) run.reflex.push_back(rt::error_name(static_cast<rt::Error>(i)));
    if (run.reflex.empty()) run.reflex.push_back(result.reason);
    run.reflex_t = emulator.state().time.toSec();
  }
  return run;
}

// Writes the plan's files, checks the trajectory independently, verifies it if asked, writes the
// report, prints it. Exit 0 for a valid plan, 1 otherwise.
int finish_plan(const PlanContext& c, Planned planned) {
  const Scene& check_scene = planned.check_scene ? *planned.check_scene : c.scene;
  PlanReport report;
  report.title = "csp plan " + c.request.command + " " + c.scene.name + " (" + robot_name(c.robot_file) + ")";
  report.command_line = "csp plan " + c.request.command + " --scene " + c.request.scene + " --robot " +
                        c.request.robot + " --seed " + std::to_string(c.request.seed);
  for (const auto& [name, value] : c.request.options) report.command_line += " --" + name + (value.empty() ? "" : " " + value);
  report.scene_name = c.scene.name;
  report.robot_name = robot_name(c.robot_file);
  report.plan = planned.made;
  report.singular_values = planned.singular_values;
  planners::write_plan_files(c.out, c.request, planners::versions(planners::ompl_version()), c.robot_file,
                             robot_armature(c.robot_file), c.scene, planned.trajectory, planned.made);
  c.progress->update("checking the trajectory", 0, 0);
  report.check = planners::check_trajectory(planned.trajectory, c.model, check_scene);
  if (c.verify) report.verify = verify_plan(c, check_scene, planned.trajectory);
  planners::write_report(c.out, report, c.scene);
  std::cout << planners::to_json(report).dump(2) << '\n';
  c.progress->finish(verdict(report) + ", files in " + c.out);
  return report.passed() ? 0 : 1;
}

// No plan: the report says why, with the best attempt; exit 1.
int no_plan(const PlanContext& c, const std::string& problem, const nlohmann::json& best_attempt) {
  PlanReport report;
  report.title = "csp plan " + c.request.command + " " + c.scene.name + ": no plan";
  report.scene_name = c.scene.name;
  report.robot_name = robot_name(c.robot_file);
  report.problems.push_back(problem);
  report.plan = best_attempt;
  report.check.passed = false;
  const nlohmann::json json = planners::to_json(report);
  fs::create_directories(c.out);
  write_text_file((fs::path(c.out) / "report.json").string(), json.dump(2) + "\n");
  std::cout << json.dump(2) << '\n';
  c.progress->finish("FAILED: no plan: " + problem + " (best attempt in " + (fs::path(c.out) / "report.json").string() + ")");
  return 1;
}

nlohmann::json joints_json(const std::vector<Vector7>& states) {
  nlohmann::json out = nlohmann::json::array();
  for (const Vector7& q : states) out.push_back(std::vector<double>(q.data(), q.data() + kNumJoints));
  return out;
}

// Rest-to-rest pieces one after the other (each starts where and when the previous ends, at rest).
void append(JointLog& whole, const JointLog& piece) {
  const bool first = whole.size() == 0;
  const double offset = first ? 0.0 : whole.t.back();
  for (std::size_t k = first ? 0 : 1; k < piece.size(); ++k) {
    whole.t.push_back(offset + piece.t[k] - piece.t.front());
    whole.q.push_back(piece.q[k]);
    whole.dq.push_back(piece.dq[k]);
    whole.ddq.push_back(piece.ddq[k]);
    whole.tau_J.push_back(piece.tau_J[k]);
  }
}

// A collision-free, timed transfer between two configurations (exit paths: no plan -> nullopt).
struct TimedPath {
  JointLog log;
  nlohmann::json made;
};
std::optional<TimedPath> transfer(const PlanContext& c, planners::ClearanceChecker& checker, const NamedPose& from,
                                  const NamedPose& to, const planners::TransferOptions& options,
                                  std::string& problem, nlohmann::json& best) {
  c.progress->update("planning transfer " + from.name + " -> " + to.name, 0, 0);
  const planners::TransferPlan plan =
      planners::plan_transfer(c.scene, checker, c.model.parameters().joint_limits, from, to, options);
  if (!plan.found) {
    problem = "transfer " + from.name + " -> " + to.name + ": " + plan.message;
    best = {{"from", from.name}, {"to", to.name}, {"best_attempt", joints_json(plan.best_attempt)},
            {"best_distance", plan.best_distance}, {"iterations", plan.iterations}, {"cap_hit", plan.cap_hit}};
    return std::nullopt;
  }
  const planners::TimedTransfer timed = planners::time_transfer(plan.waypoints, c.model);
  nlohmann::json segments = nlohmann::json::array();
  for (const planners::SegmentTiming& s : timed.segments) segments.push_back({{"duration", s.duration}, {"binding", s.binding}});
  return TimedPath{planners::trajectory_log(timed.profile, 1000.0, c.model),
                   {{"kind", "transfer"}, {"from", from.name}, {"to", to.name}, {"planner", plan.planner},
                    {"iterations", plan.iterations}, {"waypoints", joints_json(plan.waypoints)}, {"segments", segments}}};
}

// --- transfer ---

struct TransferArguments {
  PlanArguments plan;
  std::string from, to;
  std::string planner = "rrtconnect";
  long max_iterations = planners::TransferOptions{}.max_iterations;
};

int run_transfer(const TransferArguments& args, const CLI::App& command) {
  const PlanContext c = load_context("transfer", args.plan, command);
  planners::ClearanceChecker checker(c.model, c.scene);
  planners::TransferOptions options;
  options.planner = args.planner;
  options.seed = c.request.seed;
  options.max_iterations = args.max_iterations;
  std::string problem;
  nlohmann::json best;
  const std::optional<TimedPath> path =
      transfer(c, checker, c.scene.pose(args.from), c.scene.pose(args.to), options, problem, best);
  if (!path) return no_plan(c, problem, best);
  Planned planned;
  planned.trajectory = path->log;
  planned.made = {{"segments", nlohmann::json::array({path->made})}};
  return finish_plan(c, std::move(planned));
}

// --- task ---

struct TaskArguments {
  PlanArguments plan;
  int max_iterations = planners::TaskPathOptions{}.max_iterations;
};

// TaskError: an unreachable or impossible task is bad input (2); no path within the budget is no plan (1).
bool is_budget(const planners::TaskError& e) {
  return std::string(e.what()).find("no path on the constraint manifold") != std::string::npos;
}

int run_task(const TaskArguments& args, const CLI::App& command) {
  const PlanContext c = load_context("task", args.plan, command);
  planners::TaskPathOptions options;
  options.seed = static_cast<unsigned>(c.request.seed);
  options.max_iterations = args.max_iterations;
  planners::TaskPath path;
  c.progress->update("planning the task path", 0, 0);
  try {
    path = planners::plan_task_path(c.scene, c.model, options);
  } catch (const planners::TaskError& e) {
    if (is_budget(e)) return no_plan(c, e.what(), nlohmann::json());
    throw;
  }
  Planned planned;
  planned.trajectory = path.log;
  planned.made = {{"kind", "task"},          {"codim", path.codim},
                  {"start", joints_json({path.start})[0]}, {"end", joints_json({path.end})[0]},
                  {"anchors", joints_json(path.anchors)},   {"waypoints", joints_json(path.waypoints)},
                  {"iterations", path.iterations},          {"duration", path.duration}};
  planners::TaskConstraint task(c.model, c.scene);
  planned.check_scene = planners::contact_scene(c.scene, task.contact_obstacle());
  return finish_plan(c, std::move(planned));
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

// start -> anchor 1 (excite) -> anchor 2 (excite) ... -> start: one rest-to-rest trajectory. The
// anchors are the task's hover poses (its start's, its end's) or, with --anchor-placement medoids,
// the k-medoids of the task path's states (PAM, joint-space distance), each retracted along its own
// tool axis off the patient (task_anchor), in the task's order; their excitations are designed one
// after the other, each with the earlier ones' information (solve_anchors), so the criterion is the
// whole plan's.
int run_excite(const ExciteArguments& args, const CLI::App& command) {
  const PlanContext c = load_context("excite", args.plan, command);
  if (args.anchors < 1) throw UsageError("--anchors: expected 1 or more excitation anchors");
  if (args.placement != "hover" && args.placement != "medoids")
    throw UsageError("--anchor-placement: expected hover (the task's hover poses) or medoids (k-medoids of its states)");
  if (args.criterion != "task" && args.criterion != "d" && args.criterion != "cond")
    throw UsageError("--criterion: expected task (weighted toward the task's states), d (whole workspace, D-optimal) "
                     "or cond (the condition number)");
  // The task's path: its states place the anchors and, for the task-weighted criterion, weight the design.
  planners::TaskPathOptions task_options;
  task_options.seed = static_cast<unsigned>(c.request.seed);
  planners::TaskPath task;
  c.progress->update("planning the task path", 0, 0);
  try {
    task = planners::plan_task_path(c.scene, c.model, task_options);
  } catch (const planners::TaskError& e) {
    if (is_budget(e)) return no_plan(c, e.what(), nlohmann::json());
    throw;
  }
  if (args.placement == "hover" && static_cast<std::size_t>(args.anchors) > task.anchors.size())
    throw UsageError("--anchors: the task of " + c.scene.name + " has " + std::to_string(task.anchors.size()) +
                     " hover anchor(s); --anchor-placement medoids places any number");
  if (static_cast<std::size_t>(args.anchors) > task.states.size())
    throw UsageError("--anchors: the task path of " + c.scene.name + " has " + std::to_string(task.states.size()) +
                     " states to choose anchors from");
  std::vector<planners::JointSample> task_states;
  if (args.criterion != "d")   // task: weighted toward them; cond: reported on them (J_t, r_t)
    for (std::size_t k = 0; k < task.log.size(); k += 100)   // 10 Hz over the task
      task_states.push_back({task.log.q[k], task.log.dq[k], task.log.ddq[k], Vector7::Zero()});

  planners::ClearanceChecker checker(c.model, c.scene);
  planners::TaskConstraint constraint(c.model, c.scene);
  planners::Medoids medoids;   // hover: the task's first anchors (its start's and end's hover poses)
  std::vector<Vector7> anchors(task.anchors.begin(), task.anchors.begin() + std::min<std::ptrdiff_t>(args.anchors, std::ssize(task.anchors)));
  if (args.placement == "medoids") {
    medoids = planners::k_medoids(task.states, args.anchors);
    anchors.clear();
    for (const int i : medoids.indices) {
      try {
        anchors.push_back(planners::task_anchor(constraint, task.states[static_cast<std::size_t>(i)], checker));
      } catch (const planners::TaskError& e) {
        return no_plan(c, std::string("anchor at task state ") + std::to_string(i) + ": " + e.what(), nlohmann::json());
      }
    }
  }
  planners::ExcitationOptions options;
  options.harmonics = args.harmonics;
  options.fundamental_hz = args.fundamental_hz;
  options.periods = args.periods;
  options.task = task_states;
  if (args.criterion == "cond") options.design = planners::ExcitationOptions::Design::kConditionNumber;
  options.seed = static_cast<unsigned>(c.request.seed);
  options.max_evaluations = args.max_evaluations;
  options.clearance = [&checker](const Vector7& q) { return checker.check(q).clearance; };
  options.progress = c.progress->callback();
  const planners::MultiAnchorExcitation excitation = planners::solve_anchors(c.model, options, anchors);

  planners::TransferOptions transfer_options;
  transfer_options.seed = c.request.seed;
  transfer_options.max_iterations = args.transfer_iterations;
  Planned planned;
  nlohmann::json segments = nlohmann::json::array();
  NamedPose at = c.scene.pose(c.scene.start);
  std::string problem;
  nlohmann::json best;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    const NamedPose anchor{"anchor" + std::to_string(a + 1), anchors[a]};
    if (anchor.q != at.q) {   // two medoids can retract to one anchor (the burr hole's: one axis, one hover point)
      const std::optional<TimedPath> there = transfer(c, checker, at, anchor, transfer_options, problem, best);
      if (!there) return no_plan(c, problem, best);
      append(planned.trajectory, there->log);
      segments.push_back(there->made);
    }

    const planners::ExcitationResult& result = excitation.segments[a];
    append(planned.trajectory, planners::trajectory_log(result.series, result.duration, 1000.0, c.model));
    const planners::Identifiability& id = result.criteria.identifiability;
    planned.singular_values.assign(id.singular_values.data(), id.singular_values.data() + id.singular_values.size());
    nlohmann::json a_coefficients = nlohmann::json::array(), b_coefficients = nlohmann::json::array();
    for (int j = 0; j < kNumJoints; ++j) {
      a_coefficients.push_back(std::vector<double>(result.series.harmonics()));
      b_coefficients.push_back(std::vector<double>(result.series.harmonics()));
      for (int l = 0; l < result.series.harmonics(); ++l) {
        a_coefficients[j][l] = result.series.a()(j, l);
        b_coefficients[j][l] = result.series.b()(j, l);
      }
    }
    segments.push_back({{"kind", "excitation"},
                        {"anchor", joints_json({anchor.q})[0]},
                        {"fundamental_hz", result.series.fundamental_hz()},
                        {"duration", result.duration},
                        {"time_scale", result.time_scale},
                        {"a", a_coefficients},
                        {"b", b_coefficients},
                        {"q0", joints_json({result.series.q0()})[0]},
                        {"criterion", result.criteria.criterion},
                        {"best_random_start_criterion", result.best_start_criterion},
                        {"evaluations", result.evaluations},
                        {"optimizer", result.optimizer_result},
                        {"identifiability",   // of the excitations so far (this one and the earlier anchors')
                         {{"parameters", id.parameters},
                          {"rank", id.rank},
                          {"condition_number", id.condition_number},
                          {"log_det", id.log_det},
                          {"sigma_min", id.sigma_min},
                          {"task_criterion", id.task_criterion},
                          {"task_residual", id.task_residual},
                          {"task_torque_sigma", joints_json({id.task_torque_sigma})[0]}}},
                        {"limit_usage", result.usage.worst()}});
    if (!medoids.indices.empty()) segments.back()["task_state"] = medoids.indices[a];
    at = anchor;
  }
  const std::optional<TimedPath> home = transfer(c, checker, at, c.scene.pose(c.scene.start), transfer_options, problem, best);
  if (!home) return no_plan(c, problem, best);
  append(planned.trajectory, home->log);
  segments.push_back(home->made);
  planned.made = {{"criterion", args.criterion}, {"anchor_placement", args.placement}, {"segments", segments}};
  if (!medoids.indices.empty()) planned.made["medoid_distance"] = medoids.cost;
  planned.trajectory.source = "csp plan excite";
  return finish_plan(c, std::move(planned));
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
  check_command->add_option("--power-limit", check->power_limit, "Power limit [W] (the emulator's)")
      ->capture_default_str();
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
