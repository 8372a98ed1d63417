// plan_transfer: a collision-free joint-space path between two rest poses (docs/planning-transfers.md).
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/geometric/SimpleSetup.h>

#include "ompl_common.hpp"

namespace csp::planners::ompl_bridge {

using namespace detail;

Result plan_transfer(const Request& request, const Callbacks& callbacks) {
  check_request(request, callbacks, /*need_motion_check=*/true);
  const auto started = std::chrono::steady_clock::now();
  const auto plan_lock = begin_plan(request.seed);

  auto space = make_joint_space(request);
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(std::make_shared<ValidityChecker>(si.get(), callbacks));
  si->setMotionValidator(std::make_shared<CertifiedMotionValidator>(si.get(), callbacks));

  og::SimpleSetup setup(si);
  ob::ScopedState<> start(space), goal(space);
  from_joints(*space, request.start, start.get());
  from_joints(*space, request.goal, goal.get());
  setup.setStartAndGoalStates(start, goal);
  setup.getProblemDefinition()->setOptimizationObjective(std::make_shared<ob::PathLengthOptimizationObjective>(si));
  setup.setPlanner(make_planner(request.planner, si, request.range));
  setup.setup();   // the ompl#601 path: the default projection's random matrix (JacobiSVD)

  Result result;
  if (!solve_within_budget(setup, request, "path found", result, started)) return result;

  // Each shortcut is checked by the certified motion validator.
  og::PathGeometric& path = setup.getSolutionPath();
  simplify(path, si, request.simplify_steps);
  std::vector<Joints> found = waypoints(path);
  result.seconds = seconds_since(started);
  const bool passed = path_is_free(found, callbacks);
  return finish(std::move(result), std::move(found), passed, "a vertex or segment in collision");
}

}  // namespace csp::planners::ompl_bridge
