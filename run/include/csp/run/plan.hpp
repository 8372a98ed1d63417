// `csp plan`'s pipeline (docs/planning.md): the scene and the robot a plan is for, an engine (a
// transfer, the task's own path, an excitation with the transfers to its anchors), the plan's files,
// the independent check of the written trajectory, --verify (a run of the written scenario on the
// emulator, run.hpp) and the report. apps/plan_command.cpp parses the command line, calls one of
// these and prints the report; the planners know neither the emulator nor the files' places.
#pragma once

#include <string>

#include "csp/dynamics/progress.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/excitation.hpp"
#include "csp/planners/plan_files.hpp"
#include "csp/planners/planner_status.hpp"
#include "csp/planners/report.hpp"
#include "csp/planners/trajectory_check.hpp"
#include "csp/planners/transfer.hpp"

namespace csp::run {

// A shipped robot (panda, fr3) or a robot file; a shipped scene by name (configs/scenes/NAME.yaml)
// or a scene file. std::invalid_argument naming the option (--robot, --scene) otherwise.
std::string robot_file(const std::string& robot);
std::string scene_file(const std::string& scene);

// The robot with the scene's tool as its end effector (mass and TCP) and the robot file's
// armature (an FR3's motors): what a plan is made for, and what its scenario's plant is.
Model scene_model(const std::string& robot_file, const Scene& scene);

// What a planning subcommand was asked: the request plan.yaml records (its seed seeds every
// planner), the directory of the files, whether to verify on the emulator, where progress goes.
struct PlanJob {
  planners::PlanRequest request;
  std::string out;
  bool verify = false;
  Progress progress;
};

// A plan's outcome, its report written to job.out (report.json; with a plan also report.md, the
// figures and the plan's files). kNoSolution: no plan within the budget; report.problems says why
// and report.plan holds the best attempt.
struct PlanOutcome {
  planners::PlannerStatus status = planners::PlannerStatus::kNoSolution;
  planners::PlanReport report;
  bool passed() const { return status == planners::PlannerStatus::kExactSolution && report.passed(); }
};

// A collision-free transfer between two named poses of the scene (OMPL), timed.
PlanOutcome plan_transfer(const PlanJob& job, const std::string& from, const std::string& to,
                          planners::TransferOptions options);

// The medical task's own path on its constraint manifold, timed.
PlanOutcome plan_task(const PlanJob& job, int max_iterations);

// An excitation for identification: start -> anchor 1 (excite) -> anchor 2 (excite) ... -> start.
struct ExcitationJob {
  int anchors = 1;
  std::string placement = "hover";   // hover (the task's hover poses) or medoids (k-medoids of its states)
  std::string criterion = "task";    // task (weighted toward the task), d (D-optimal) or cond
  planners::ExcitationOptions options;   // harmonics, fundamental, periods, max_evaluations (the rest is set here)
  long transfer_iterations = planners::TransferOptions{}.max_iterations;
};
PlanOutcome plan_excitation(const PlanJob& job, const ExcitationJob& excitation);

// `csp plan check`: any trajectory file against a scene and the robot's limits; the report also in
// `out` when it is not empty.
planners::PlanReport check_trajectory_file(const std::string& trajectory, const std::string& scene,
                                           const std::string& robot, const planners::CheckOptions& options,
                                           const std::string& out);

}  // namespace csp::run
