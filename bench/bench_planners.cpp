// csp_planner_bench: collision check of one state (forward kinematics, then the arm's and the tool's
// capsules against a shipped scene and against the arm itself; issue target <= 5 us), with the
// broad phase (bounding boxes, exact distance only where it could beat the tightest pair so far)
// and without it (every pair exactly: the naive baseline), side by side on the same states.
#include <chrono>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "csp/planners/checker.hpp"
#include "planner_support.hpp"

namespace {

using namespace csp;

using bench::kShippedScenes;

struct Fixture {
  explicit Fixture(int scene_index)
      : scene(bench::shipped_scene(scene_index)), model(bench::panda_with_tool(scene)), checker(model, scene) {
    // 1024 states uniform in the joint limits (valid and invalid alike), seeded.
    std::mt19937_64 engine(1);
    const JointLimits& limits = model.parameters().joint_limits;
    for (int k = 0; k < 1024; ++k) {
      Vector7 q;
      for (int i = 0; i < kNumJoints; ++i)
        q[i] = std::uniform_real_distribution<double>(limits.q_min[i], limits.q_max[i])(engine);
      states.push_back(q);
    }
  }
  Scene scene;
  Model model;
  planners::ClearanceChecker checker;
  std::vector<Vector7> states;
};

template <bool kBroadPhase>
void BM_CheckState(benchmark::State& state) {
  Fixture f(static_cast<int>(state.range(0)));
  std::size_t k = 0;
  for (auto _ : state) {
    const Vector7& q = f.states[k++ & 1023];
    const planners::StateClearance c = kBroadPhase ? f.checker.check(q) : f.checker.check_all_pairs(q);
    benchmark::DoNotOptimize(c.clearance);
  }
  state.SetLabel(kShippedScenes[state.range(0)]);
  state.counters["pairs"] = f.checker.num_pairs();
  if (kBroadPhase) {   // the ratio to the naive baseline, both timed here on the same states under the same load
    auto per_state_ns = [&](bool broad) {
      const auto start = std::chrono::steady_clock::now();
      for (int repeat = 0; repeat < 20; ++repeat)
        for (const Vector7& q : f.states)
          benchmark::DoNotOptimize((broad ? f.checker.check(q) : f.checker.check_all_pairs(q)).clearance);
      return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() / (20.0 * 1024);
    };
    const double broad_ns = per_state_ns(true), naive_ns = per_state_ns(false);
    state.counters["naive_over_broad"] = naive_ns / broad_ns;
  }
}
BENCHMARK_TEMPLATE(BM_CheckState, true)->DenseRange(0, 3)->Unit(benchmark::kNanosecond);
BENCHMARK_TEMPLATE(BM_CheckState, false)->DenseRange(0, 3)->Unit(benchmark::kNanosecond);

// A certified motion check of a 0.1 rad step on every joint from valid states.
void BM_MotionCheck(benchmark::State& state) {
  Fixture f(static_cast<int>(state.range(0)));
  std::vector<Vector7> valid;
  for (const Vector7& q : f.states)
    if (f.checker.is_valid(q)) valid.push_back(q);
  std::size_t k = 0, certified = 0;
  for (auto _ : state) {
    const Vector7& q = valid[k++ % valid.size()];
    certified += f.checker.motion_is_free(q, q + Vector7::Constant(0.1)) ? 1 : 0;
  }
  state.SetLabel(kShippedScenes[state.range(0)]);
  state.counters["certified_fraction"] = static_cast<double>(certified) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_MotionCheck)->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
