// How a planning query ended, typed as OMPL's ompl::base::PlannerStatus is, so that callers tell
// the outcomes apart without reading messages. A query that cannot be asked (an unreachable task,
// a pose in collision) is not a status: it throws, naming what was wrong.
#pragma once

namespace csp::planners {

enum class PlannerStatus {
  kExactSolution,   // a path that reaches the goal (OMPL's EXACT_SOLUTION)
  kNoSolution,      // none within the planner's budget (OMPL's TIMEOUT: its iteration cap)
};

}  // namespace csp::planners
