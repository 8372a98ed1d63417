// `csp plan check` of a 100 s trajectory at 1 kHz (100 001 samples: limits by the robot's finite
// differences, the torque by RNEA, the TCP speed, the clearance per obstacle class with the broad
// phase, every motion between samples certified), target <= 2 s; beside it the naive baseline, every
// pair exactly at every sample (the same limits and certification), and their ratio.
//
//   ./build/bench/csp_plan_check_bench
#include <chrono>
#include <random>
#include <utility>

#include <benchmark/benchmark.h>

#include "csp/planners/fourier.hpp"
#include "csp/planners/trajectory_check.hpp"
#include "planner_support.hpp"

namespace {

using namespace csp;

// A seeded rest-to-rest excitation of 10 periods of 10 s around the scene's start pose.
const JointLog& trajectory(const Scene& scene, const Model& model) {
  static const JointLog log = [&] {
    std::mt19937 random(11);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Eigen::MatrixXd free(kNumJoints, 7);
    for (Eigen::Index i = 0; i < free.size(); ++i) free(i) = 0.1 * uniform(random);
    const auto series = planners::FourierSeries::rest_to_rest(0.1, 5, free, scene.pose(scene.start).q);
    return planners::trajectory_log(series, 100.0, 1000.0, model);
  }();
  return log;
}

void check(benchmark::State& state, bool broad_phase) {
  const Scene scene = bench::shipped_scene(0);
  const Model model = bench::panda_with_tool(scene);
  const JointLog& log = trajectory(scene, model);
  planners::CheckOptions options;
  options.broad_phase = broad_phase;
  bool passed = false;
  for (auto _ : state) {
    const planners::TrajectoryCheck result = planners::check_trajectory(log, model, scene, options);
    passed = result.passed;
    benchmark::DoNotOptimize(result.clearance.data());
  }
  state.counters["samples"] = static_cast<double>(log.size());
  state.counters["passed"] = passed ? 1.0 : 0.0;
}

void BM_PlanCheck100s(benchmark::State& state) { check(state, true); }
void BM_PlanCheck100sNaiveAllPairs(benchmark::State& state) { check(state, false); }

// Both in one loop, alternating, so that the ratio is measured under the same machine load.
void BM_PlanCheck100sRatioNaiveOverBroad(benchmark::State& state) {
  const Scene scene = bench::shipped_scene(0);
  const Model model = bench::panda_with_tool(scene);
  const JointLog& log = trajectory(scene, model);
  planners::CheckOptions broad, naive;
  naive.broad_phase = false;
  double broad_seconds = 0.0, naive_seconds = 0.0;
  for (auto _ : state) {
    for (auto [options, seconds] : {std::pair{&broad, &broad_seconds}, std::pair{&naive, &naive_seconds}}) {
      const auto start = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(planners::check_trajectory(log, model, scene, *options).passed);
      *seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  }
  state.counters["broad_s"] = broad_seconds / static_cast<double>(state.iterations());
  state.counters["naive_s"] = naive_seconds / static_cast<double>(state.iterations());
  state.counters["naive_over_broad"] = naive_seconds / broad_seconds;
}

BENCHMARK(BM_PlanCheck100s)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_PlanCheck100sNaiveAllPairs)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_PlanCheck100sRatioNaiveOverBroad)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
