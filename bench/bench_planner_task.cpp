// csp_planner_task_bench: the medical task's own path per shipped scene (plan_task_path: IK of the
// task's start, end and anchors, OMPL's constrained RRTConnect on the task manifold, densification
// and projection, timing, the 1 kHz log; issue target <= 5 s). Side by side in the same run, the
// naive baseline: the same plan with OMPL's default numerical constraint Jacobian (central
// differences inside ompl::base::Constraint) instead of the analytic one. Counters: the planner's
// own share (OMPL set-up, solve, simplification, geodesic interpolation) and the path's duration.
#include <string>

#include <benchmark/benchmark.h>

#include "csp/planners/task.hpp"
#include "planner_support.hpp"

namespace {

using namespace csp;

template <bool kAnalytic>
void BM_TaskPath(benchmark::State& state) {
  const Scene scene = bench::shipped_scene(static_cast<int>(state.range(0)));
  const Model model = bench::panda_with_tool(scene);
  planners::TaskPathOptions options;
  options.analytic_jacobian = kAnalytic;
  double planning = 0.0, duration = 0.0;
  for (auto _ : state) {
    const planners::TaskPath path = planners::plan_task_path(scene, model, options);
    planning += path.planning_seconds;
    duration = path.duration;
    benchmark::DoNotOptimize(path.log.q.data());
  }
  state.SetLabel(bench::kShippedScenes[static_cast<std::size_t>(state.range(0))] +
                 (kAnalytic ? " analytic Jacobian" : " numerical Jacobian (OMPL default)"));
  state.counters["ompl_ms"] = benchmark::Counter(1e3 * planning / static_cast<double>(state.iterations()));
  state.counters["path_s"] = duration;
}

BENCHMARK(BM_TaskPath<true>)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TaskPath<false>)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
