// csp_planner_transfer_bench: one transfer plan per shipped scene (OMPL's RRTConnect through
// csp_ompl_bridge, issue target <= 1 s), from the scene's start pose to a seeded goal whose straight
// motion is blocked (the shipped poses are joined by straight motions, which take a millisecond).
// Side by side in the same run, the naive baseline: the same plan with the motion checked state by
// state at joint steps of 0.002 rad (OMPL's discrete motion validator at a resolution fine enough
// for this arm, planning-notes section 9.4) instead of the certified check (Schwarzer et al. 2005).
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "csp/planners/checker.hpp"
#include "planner_support.hpp"
#include "csp/planners/ompl_bridge.hpp"

namespace {

using namespace csp;
namespace bridge = planners::ompl_bridge;

using bench::kShippedScenes;
constexpr double kNaiveStep = 0.002;   // [rad]
constexpr double kMargin = 0.05;       // TransferOptions' default [rad]

Vector7 vector(const bridge::Joints& q) { return Eigen::Map<const Vector7>(q.data()); }
bridge::Joints joints(const Vector7& q) {
  bridge::Joints out;
  Eigen::Map<Vector7>(out.data()) = q;
  return out;
}

struct Fixture {
  explicit Fixture(int scene_index)
      : scene(bench::shipped_scene(scene_index)), model(bench::panda_with_tool(scene)), checker(model, scene) {
    const JointLimits& limits = model.parameters().joint_limits;
    const Vector7 start = scene.pose(scene.start).q;
    request.start = joints(start);
    request.lower = joints(limits.q_min.array() + kMargin);
    request.upper = joints(limits.q_max.array() - kMargin);
    // The first seeded valid goal that the straight motion cannot reach.
    std::mt19937_64 engine(1);
    Vector7 goal;
    do {
      for (int i = 0; i < kNumJoints; ++i)
        goal[i] = std::uniform_real_distribution<double>(request.lower[i], request.upper[i])(engine);
    } while (!checker.is_valid(goal) || checker.motion_is_free(start, goal));
    request.goal = joints(goal);
  }

  bridge::Callbacks callbacks(bool certified) {
    bridge::Callbacks c;
    c.is_valid = [this](const bridge::Joints& q) { return checker.is_valid(vector(q)); };
    if (certified) {
      c.motion_is_free = [this](const bridge::Joints& a, const bridge::Joints& b) {
        return checker.motion_is_free(vector(a), vector(b));
      };
    } else {
      c.motion_is_free = [this](const bridge::Joints& a, const bridge::Joints& b) {
        const Vector7 qa = vector(a), d = vector(b) - qa;
        const int steps = std::max(1, static_cast<int>(std::ceil(d.cwiseAbs().maxCoeff() / kNaiveStep)));
        for (int s = 1; s <= steps; ++s)
          if (!checker.is_valid(qa + d * (static_cast<double>(s) / steps))) return false;
        return true;
      };
    }
    return c;
  }

  Scene scene;
  Model model;
  planners::ClearanceChecker checker;
  bridge::Request request;
};

template <bool kCertified>
void BM_Transfer(benchmark::State& state) {
  Fixture f(static_cast<int>(state.range(0)));
  const bridge::Callbacks callbacks = f.callbacks(kCertified);
  bridge::Result result;
  for (auto _ : state) result = bridge::plan_transfer(f.request, callbacks);
  state.SetLabel(kShippedScenes[state.range(0)] + (result.solved ? "" : " (not solved: " + result.message + ")"));
  state.counters["waypoints"] = static_cast<double>(result.waypoints.size());
  state.counters["iterations"] = static_cast<double>(result.iterations);
  if (kCertified) {   // the ratio to the naive baseline, both timed here on the same problem under the same load
    auto plan_seconds = [&](const bridge::Callbacks& c) {
      const auto start = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(bridge::plan_transfer(f.request, c).solved);
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    const double certified = plan_seconds(callbacks), naive = plan_seconds(f.callbacks(false));
    state.counters["naive_over_certified"] = naive / certified;
  }
}
BENCHMARK_TEMPLATE(BM_Transfer, true)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Transfer, false)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
