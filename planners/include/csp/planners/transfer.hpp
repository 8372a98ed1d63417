// Collision-free transfers between rest poses (home, excitation anchors, the task start) in a scene:
// OMPL (through csp_ompl_bridge) over the ClearanceChecker, with its certified motion check
// (docs/planning-transfers.md). Time the waypoints with profile.hpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "csp/dynamics/limits.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/planner_status.hpp"

namespace csp::planners {

struct TransferOptions {
  std::string planner = "rrtconnect";   // rrtconnect | rrtstar | bitstar | lazyprmstar (transfer_planners())
  std::uint64_t seed = 1;               // 1 .. 2^32-1; the same seed gives the same waypoints in any process
  long max_iterations = 20000;          // the planner's budget (loop iterations; no wall-clock limit)
  int simplify_steps = 100;             // path simplification budget per pass; 0: the planner's raw path
  double limit_margin = 0.05;           // the planned path stays this far inside q_min, q_max [rad]
};

struct TransferPlan {
  PlannerStatus status = PlannerStatus::kNoSolution;
  bool found() const { return status == PlannerStatus::kExactSolution; }
  std::vector<Vector7> waypoints;       // from ... to (rest at each), when found
  // When not found: the planner's best attempt (valid, certified, but short of the goal) and how far
  // its end is from the goal [rad] (-1: none); `message` says why.
  std::vector<Vector7> best_attempt;
  double best_distance = -1.0;
  long iterations = 0;
  bool cap_hit = false;
  double seconds = 0.0;                 // wall time, informative only
  long state_checks = 0, motion_checks = 0;
  std::string planner, message;
};

// Plans from `from` to `to` with the scene's checker (built on the same scene and robot). Throws
// std::invalid_argument, naming the pose and what is wrong, for bad input: a pose in collision
// (with the pair, its class and clearance), a pose outside the joint limits minus the margin, an
// unknown planner, a bad budget. Not finding a path within the budget is not an exception.
TransferPlan plan_transfer(const Scene& scene, ClearanceChecker& checker, const JointLimits& limits,
                           const NamedPose& from, const NamedPose& to, const TransferOptions& options = {});

std::vector<std::string> transfer_planners();
std::string ompl_version();

}  // namespace csp::planners
