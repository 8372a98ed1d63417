#include "csp/run/plan.hpp"

#include <filesystem>
#include <limits>
#include <optional>

#include "csp/io/robot_config.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/kmedoids.hpp"
#include "csp/planners/profile.hpp"
#include "csp/planners/task.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace csp::run {
namespace {

namespace fs = std::filesystem;
using planners::PlannerStatus;
using planners::PlanReport;

std::string robot_name(const std::string& robot) { return fs::path(robot).stem().string(); }

// The loaded inputs of a plan.
struct PlanContext {
  const PlanJob& job;
  Scene scene;
  std::string robot_file;
  Model model;
};

PlanContext load_context(const PlanJob& job) {
  if (job.out.empty()) throw std::invalid_argument("--out: expected the directory to write the plan into");
  Scene scene = load_scene(scene_file(job.request.scene));
  const std::string robot = robot_file(job.request.robot);
  Model model = scene_model(robot, scene);
  return {job, std::move(scene), robot, std::move(model)};
}

// What an engine made: the 1 kHz trajectory, its own record, and the scene its trajectory is checked
// against (a task's tool touches the patient by design: contact_scene).
struct Planned {
  JointLog trajectory;
  nlohmann::json made = nlohmann::json::object();
  std::vector<double> singular_values;
  std::optional<Scene> check_scene;
};

// Clearance of the measured motion to each obstacle class: the closest approach and where.
class ClearanceObserver : public Observer {
 public:
  ClearanceObserver(const Model& model, const Scene& scene, const rt::Emulator& emulator)
      : checker_(model, scene), time_(emulator) {
    for (const std::string& name : checker_.classes())
      closest_.push_back({name, std::numeric_limits<double>::infinity(), 0.0, 0.0, "", ""});
  }
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override {
    const std::vector<planners::StateClearance>& by_class = checker_.check_by_class(Vector7(state.q.data()));
    for (std::size_t k = 0; k < by_class.size(); ++k)
      if (by_class[k].clearance < closest_[k].clearance)
        closest_[k] = {checker_.classes()[k], by_class[k].clearance, by_class[k].distance, time_.of(state),
                       std::string(by_class[k].moving), std::string(by_class[k].other)};
  }
  const std::vector<planners::ClassClearance>& closest() const { return closest_; }

 private:
  planners::ClearanceChecker checker_;
  MotionTime time_;
  std::vector<planners::ClassClearance> closest_;
};

// --verify: the written scenario run on the emulator (lockstep, as `csp emulate` runs it), the
// measured motion compared with the plan and checked against the scene.
planners::EmulatorRun verify_plan(const PlanContext& c, const Scene& scene, const JointLog& trajectory) {
  Run run(rt::load_scenario((fs::path(c.job.out) / "scenario.yaml").string()));
  const double duration = run.scenario().duration;
  ProgressObserver progress(c.job.progress, "verifying on the emulator (simulated seconds)", duration, run.emulator());
  TrackingObserver tracking(
      [&trajectory](double t) {
        return trajectory.q[std::min(trajectory.size() - 1, static_cast<std::size_t>(std::lround(t * 1000.0)))];
      },
      run.emulator());
  ClearanceObserver clearance(c.model, scene, run.emulator());
  run.observe(progress);
  run.observe(tracking);
  run.observe(clearance);
  ControllerSource controller(run);
  run.run(controller);

  planners::EmulatorRun verified;
  verified.robot = robot_name(c.robot_file);
  verified.duration = tracking.last_time();
  verified.tracking_rms = tracking.rms_error();
  verified.tracking_max = tracking.max_error();
  verified.peak_tau_J_fraction = tracking.peak_tau_J_fraction();
  verified.measured_clearance = clearance.closest();
  if (controller.reflex()) {
    for (int i = 0; i < rt::kNumErrors; ++i)
      if (controller.motion().errors.flags()[i]) verified.reflex.push_back(rt::error_name(static_cast<rt::Error>(i)));
    if (verified.reflex.empty()) verified.reflex.push_back(run.emulator().reflex_reason());
    verified.reflex_t = run.emulator().state().time.toSec();
  }
  return verified;
}

// Writes the plan's files, checks the trajectory independently, verifies it if asked, writes the
// report.
PlanOutcome finish_plan(const PlanContext& c, Planned planned) {
  const PlanJob& job = c.job;
  const Scene& check_scene = planned.check_scene ? *planned.check_scene : c.scene;
  PlanOutcome outcome;
  outcome.status = PlannerStatus::kExactSolution;
  PlanReport& report = outcome.report;
  report.title = "csp plan " + job.request.command + " " + c.scene.name + " (" + robot_name(c.robot_file) + ")";
  report.command_line = "csp plan " + job.request.command + " --scene " + job.request.scene + " --robot " +
                        job.request.robot + " --seed " + std::to_string(job.request.seed);
  for (const auto& [name, value] : job.request.options) report.command_line += " --" + name + (value.empty() ? "" : " " + value);
  report.scene_name = c.scene.name;
  report.robot_name = robot_name(c.robot_file);
  report.plan = planned.made;
  report.singular_values = planned.singular_values;
  planners::write_plan_files(job.out, job.request, planners::versions(planners::ompl_version()), c.robot_file, c.scene,
                             planned.trajectory, planned.made);
  csp::report(job.progress, "checking the trajectory", 0, 0);
  report.check = planners::check_trajectory(planned.trajectory, c.model, check_scene);
  if (job.verify) report.verify = verify_plan(c, check_scene, planned.trajectory);
  planners::write_report(job.out, report, c.scene);
  return outcome;
}

// No plan: the report says why, with the best attempt (report.json only).
PlanOutcome no_plan(const PlanContext& c, const std::string& problem, const nlohmann::json& best_attempt) {
  PlanOutcome outcome;
  outcome.status = PlannerStatus::kNoSolution;
  PlanReport& report = outcome.report;
  report.title = "csp plan " + c.job.request.command + " " + c.scene.name + ": no plan";
  report.scene_name = c.scene.name;
  report.robot_name = robot_name(c.robot_file);
  report.problems.push_back(problem);
  report.plan = best_attempt;
  report.check.passed = false;
  fs::create_directories(c.job.out);
  write_text_file((fs::path(c.job.out) / "report.json").string(), planners::to_json(report).dump(2) + "\n");
  return outcome;
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

// A collision-free, timed transfer between two configurations; without one, `problem` and `best`
// (the planner's best attempt) say why.
struct TimedPath {
  JointLog log;
  nlohmann::json made;
};
std::optional<TimedPath> transfer(const PlanContext& c, planners::ClearanceChecker& checker, const NamedPose& from,
                                  const NamedPose& to, const planners::TransferOptions& options,
                                  std::string& problem, nlohmann::json& best) {
  csp::report(c.job.progress, "planning transfer " + from.name + " -> " + to.name, 0, 0);
  const planners::TransferPlan plan =
      planners::plan_transfer(c.scene, checker, c.model.parameters().joint_limits, from, to, options);
  if (!plan.found()) {
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

// The excitation segment's record in plan.yaml's `made`: its series and the identifiability so far.
nlohmann::json excitation_record(const Vector7& anchor, const planners::ExcitationResult& result) {
  const planners::Identifiability& id = result.criteria.identifiability;
  nlohmann::json a_coefficients = nlohmann::json::array(), b_coefficients = nlohmann::json::array();
  for (int j = 0; j < kNumJoints; ++j) {
    a_coefficients.push_back(std::vector<double>(result.series.harmonics()));
    b_coefficients.push_back(std::vector<double>(result.series.harmonics()));
    for (int l = 0; l < result.series.harmonics(); ++l) {
      a_coefficients[j][l] = result.series.a()(j, l);
      b_coefficients[j][l] = result.series.b()(j, l);
    }
  }
  return {{"kind", "excitation"},
          {"anchor", joints_json({anchor})[0]},
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
          {"limit_usage", result.usage.worst()}};
}

}  // namespace

std::string robot_file(const std::string& robot) {
  if (robot == "panda" || robot == "fr3") return rt::shipped_config_dir() + "/robots/" + robot + ".yaml";
  if (!fs::is_regular_file(robot))
    throw std::invalid_argument("--robot: expected panda, fr3 or a robot file (`" + robot + "` is not a readable file)");
  return robot;
}

std::string scene_file(const std::string& scene) {
  const std::string shipped = rt::shipped_config_dir() + "/scenes/" + scene + ".yaml";
  if (scene.find('/') == std::string::npos && scene.find('.') == std::string::npos && fs::is_regular_file(shipped))
    return shipped;
  if (!fs::is_regular_file(scene))
    throw std::invalid_argument("--scene: expected a scene file or the name of a shipped scene (configs/scenes/), got `" +
                                scene + "`");
  return scene;
}

Model scene_model(const std::string& robot_file, const Scene& scene) {
  const RobotConfig config = load_robot_config(robot_file);
  ModelParameters parameters = with_tool(model_parameters(config, {}), scene.tool);
  parameters.armature = config.armature.values;   // the plan's scenario's plant has it (robot.yaml)
  return Model(parameters);
}

PlanOutcome plan_transfer(const PlanJob& job, const std::string& from, const std::string& to,
                          planners::TransferOptions options) {
  const PlanContext c = load_context(job);
  planners::ClearanceChecker checker(c.model, c.scene);
  options.seed = job.request.seed;
  std::string problem;
  nlohmann::json best;
  const std::optional<TimedPath> path = transfer(c, checker, c.scene.pose(from), c.scene.pose(to), options, problem, best);
  if (!path) return no_plan(c, problem, best);
  Planned planned;
  planned.trajectory = path->log;
  planned.made = {{"segments", nlohmann::json::array({path->made})}};
  return finish_plan(c, std::move(planned));
}

PlanOutcome plan_task(const PlanJob& job, int max_iterations) {
  const PlanContext c = load_context(job);
  planners::TaskPathOptions options;
  options.seed = static_cast<unsigned>(job.request.seed);
  options.max_iterations = max_iterations;
  csp::report(job.progress, "planning the task path", 0, 0);
  const planners::TaskPath path = planners::plan_task_path(c.scene, c.model, options);
  if (path.status != PlannerStatus::kExactSolution) return no_plan(c, path.message, nlohmann::json());
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

// The anchors are the task's hover poses (its start's, its end's) or, with the medoids placement,
// the k-medoids of the task path's states (PAM, joint-space distance), each retracted along its own
// tool axis off the patient (task_anchor), in the task's order; their excitations are designed one
// after the other, each with the earlier ones' information (solve_anchors), so the criterion is the
// whole plan's.
PlanOutcome plan_excitation(const PlanJob& job, const ExcitationJob& excitation) {
  const PlanContext c = load_context(job);
  if (excitation.anchors < 1) throw std::invalid_argument("--anchors: expected 1 or more excitation anchors");
  if (excitation.placement != "hover" && excitation.placement != "medoids")
    throw std::invalid_argument("--anchor-placement: expected hover (the task's hover poses) or medoids (k-medoids of its states)");
  if (excitation.criterion != "task" && excitation.criterion != "d" && excitation.criterion != "cond")
    throw std::invalid_argument("--criterion: expected task (weighted toward the task's states), d (whole workspace, "
                                "D-optimal) or cond (the condition number)");
  // The task's path: its states place the anchors and, for the task-weighted criterion, weight the design.
  planners::TaskPathOptions task_options;
  task_options.seed = static_cast<unsigned>(job.request.seed);
  csp::report(job.progress, "planning the task path", 0, 0);
  const planners::TaskPath task = planners::plan_task_path(c.scene, c.model, task_options);
  if (task.status != PlannerStatus::kExactSolution) return no_plan(c, task.message, nlohmann::json());
  if (excitation.placement == "hover" && static_cast<std::size_t>(excitation.anchors) > task.anchors.size())
    throw std::invalid_argument("--anchors: the task of " + c.scene.name + " has " + std::to_string(task.anchors.size()) +
                                " hover anchor(s); --anchor-placement medoids places any number");
  if (static_cast<std::size_t>(excitation.anchors) > task.states.size())
    throw std::invalid_argument("--anchors: the task path of " + c.scene.name + " has " + std::to_string(task.states.size()) +
                                " states to choose anchors from");
  std::vector<planners::JointSample> task_states;
  if (excitation.criterion != "d")   // task: weighted toward them; cond: reported on them (J_t, r_t)
    for (std::size_t k = 0; k < task.log.size(); k += 100)   // 10 Hz over the task
      task_states.push_back({task.log.q[k], task.log.dq[k], task.log.ddq[k], Vector7::Zero()});

  planners::ClearanceChecker checker(c.model, c.scene);
  planners::TaskConstraint constraint(c.model, c.scene);
  planners::Medoids medoids;   // hover: the task's first anchors (its start's and end's hover poses)
  std::vector<Vector7> anchors(task.anchors.begin(),
                               task.anchors.begin() + std::min<std::ptrdiff_t>(excitation.anchors, std::ssize(task.anchors)));
  if (excitation.placement == "medoids") {
    medoids = planners::k_medoids(task.states, excitation.anchors);
    anchors.clear();
    for (const int i : medoids.indices) {
      try {
        anchors.push_back(planners::task_anchor(constraint, task.states[static_cast<std::size_t>(i)], checker));
      } catch (const planners::TaskError& e) {
        return no_plan(c, std::string("anchor at task state ") + std::to_string(i) + ": " + e.what(), nlohmann::json());
      }
    }
  }
  planners::ExcitationOptions options = excitation.options;
  options.task = task_states;
  if (excitation.criterion == "cond") options.design = planners::ExcitationOptions::Design::kConditionNumber;
  options.seed = static_cast<unsigned>(job.request.seed);
  options.clearance = [&checker](const Vector7& q) { return checker.check(q).clearance; };
  options.progress = job.progress;
  const planners::MultiAnchorExcitation designed = planners::solve_anchors(c.model, options, anchors);

  planners::TransferOptions transfer_options;
  transfer_options.seed = job.request.seed;
  transfer_options.max_iterations = excitation.transfer_iterations;
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
    const planners::ExcitationResult& result = designed.segments[a];
    append(planned.trajectory, planners::trajectory_log(result.series, result.duration, 1000.0, c.model));
    const planners::Identifiability& id = result.criteria.identifiability;
    planned.singular_values.assign(id.singular_values.data(), id.singular_values.data() + id.singular_values.size());
    segments.push_back(excitation_record(anchor.q, result));
    if (!medoids.indices.empty()) segments.back()["task_state"] = medoids.indices[a];
    at = anchor;
  }
  const std::optional<TimedPath> home = transfer(c, checker, at, c.scene.pose(c.scene.start), transfer_options, problem, best);
  if (!home) return no_plan(c, problem, best);
  append(planned.trajectory, home->log);
  segments.push_back(home->made);
  planned.made = {{"criterion", excitation.criterion}, {"anchor_placement", excitation.placement}, {"segments", segments}};
  if (!medoids.indices.empty()) planned.made["medoid_distance"] = medoids.cost;
  planned.trajectory.source = "csp plan excite";
  return finish_plan(c, std::move(planned));
}

PlanReport check_trajectory_file(const std::string& trajectory, const std::string& scene, const std::string& robot,
                                 const planners::CheckOptions& options, const std::string& out) {
  const Scene loaded = load_scene(scene_file(scene));
  const std::string robot_path = robot_file(robot);
  const Model model = scene_model(robot_path, loaded);
  if (!(options.power_limit >= 0.0))
    throw std::invalid_argument("--power-limit: expected a power >= 0 [W] (0: the robot file's)");
  if (options.tool_speed_limit < 0.0)
    throw std::invalid_argument("--tool-speed: expected a speed >= 0 [m/s] (0: the robot file's)");
  const JointLog log = read_joint_log_csv(trajectory);
  PlanReport report;
  report.title = "csp plan check " + fs::path(trajectory).filename().string();
  report.command_line = "csp plan check " + trajectory + " --scene " + scene + " --robot " + robot;
  report.scene_name = loaded.name;
  report.robot_name = robot_name(robot_path);
  report.check = planners::check_trajectory(log, model, loaded, options);
  if (!out.empty()) planners::write_report(out, report, loaded);
  return report;
}

}  // namespace csp::run
