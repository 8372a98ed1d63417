// csp_excitation_bench: the excitation design (docs/excitation.md). One full optimisation per scene's
// anchor (20 random starts, then MMA with the default 300-evaluation budget; issue target <= 60 s), and the
// criterion gradient: analytic through the Fourier terms (7 RNEA per state and state component) vs
// the naive baseline, forward differences of the whole criterion (one criterion per coefficient),
// side by side on the same coefficients.
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "csp/io/robot_config.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/excitation.hpp"

namespace {

using namespace csp;

struct Anchor {
  std::string scene, pose, task_to;   // task_to: the task is a slow sweep from `pose` to it; empty: D-optimal
};
const std::vector<Anchor> kAnchors = {{"ultrasound_abdomen", "scan_start_hover", "scan_end_hover"},
                                      {"doppler_femoral", "scan_start_hover", "scan_end_hover"},
                                      {"mis_rcm", "port_hover", ""},
                                      {"craniotomy", "burr_hover", ""}};

// A straight joint-space sweep a -> b over 15 s, septic timing, at 10 Hz.
std::vector<planners::JointSample> sweep(const Vector7& a, const Vector7& b) {
  std::vector<planners::JointSample> samples;
  for (int k = 0; k <= 150; ++k) {
    const double u = k / 150.0, T = 15.0;
    planners::JointSample s;
    s.q = a + (35 * std::pow(u, 4) - 84 * std::pow(u, 5) + 70 * std::pow(u, 6) - 20 * std::pow(u, 7)) * (b - a);
    s.dq = (140 * std::pow(u, 3) - 420 * std::pow(u, 4) + 420 * std::pow(u, 5) - 140 * std::pow(u, 6)) / T * (b - a);
    s.ddq = (420 * u * u - 1680 * std::pow(u, 3) + 2100 * std::pow(u, 4) - 840 * std::pow(u, 5)) / (T * T) * (b - a);
    samples.push_back(s);
  }
  return samples;
}

struct Fixture {
  explicit Fixture(const Anchor& anchor)
      : scene(load_scene(std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + anchor.scene + ".yaml")),
        model(with_tool(
            model_parameters(load_robot_config(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"), {}), scene.tool)),
        checker(std::make_shared<planners::ClearanceChecker>(model, scene)) {
    const Vector7 a = scene.pose(anchor.pose).q;
    options.anchor = a;
    if (!anchor.task_to.empty()) {
      const Vector7 b = scene.pose(anchor.task_to).q;
      options.anchor = 0.5 * (a + b);
      options.task = sweep(a, b);
    }
    auto c = checker;
    options.clearance = [c](const Vector7& q) { return c->check(q).clearance; };
  }
  Scene scene;
  Model model;
  std::shared_ptr<planners::ClearanceChecker> checker;
  planners::ExcitationOptions options;
};

void BM_ExcitationOptimisation(benchmark::State& state) {
  const Anchor& anchor = kAnchors[static_cast<std::size_t>(state.range(0))];
  Fixture f(anchor);
  std::optional<planners::ExcitationResult> solved;
  for (auto _ : state) {
    const planners::ExcitationProblem problem(f.model, f.options);
    solved = problem.solve();
  }
  const planners::ExcitationResult& result = *solved;
  state.SetLabel(anchor.scene + (anchor.task_to.empty() ? " D-optimal" : " task-weighted"));
  const auto& id = result.criteria.identifiability;
  state.counters["Phi"] = result.criteria.criterion;
  state.counters["Phi_best_start"] = result.best_start_criterion;
  state.counters["kappa"] = id.condition_number;
  state.counters["log_det"] = id.log_det;
  state.counters["rank"] = id.rank;
  if (!anchor.task_to.empty()) {
    state.counters["J_t"] = id.task_criterion;
    state.counters["r_t"] = id.task_residual;
  }
  state.counters["evaluations"] = result.evaluations;
  state.counters["time_scale"] = result.time_scale;
  state.counters["amplitude_scale"] = result.amplitude_scale;
  state.counters["min_clearance_mm"] = 1e3 * result.usage.min_clearance;
  state.counters["within_limits"] = result.usage.within();
}

void BM_CriterionGradient(benchmark::State& state) {
  Fixture f(kAnchors[0]);
  const planners::ExcitationProblem problem(f.model, f.options);
  const std::vector<double> x = problem.random_start(1);
  std::vector<double> gradient;
  const auto analytic = [&] { return problem.criterion(x, &gradient); };
  const auto naive = [&] {   // forward differences of the whole criterion
    const double h = 1e-6, value = problem.criterion(x, nullptr);
    std::vector<double> fd(x.size()), moved = x;
    for (std::size_t i = 0; i < x.size(); ++i) {
      moved[i] += h;
      fd[i] = (problem.criterion(moved, nullptr) - value) / h;
      moved[i] = x[i];
    }
    return fd[0];
  };
  for (auto _ : state) benchmark::DoNotOptimize(analytic());
  // Both timed here on the same coefficients under the same load.
  const auto seconds = [](const auto& f) {
    const auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(f());
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const double a = seconds(analytic), n = seconds(naive);
  state.counters["analytic_ms"] = 1e3 * a;
  state.counters["naive_fd_ms"] = 1e3 * n;
  state.counters["naive/analytic"] = n / a;
  state.counters["variables"] = problem.variables();
}

void BM_Criterion(benchmark::State& state) {
  Fixture f(kAnchors[0]);
  const planners::ExcitationProblem problem(f.model, f.options);
  const std::vector<double> x = problem.random_start(1);
  for (auto _ : state) benchmark::DoNotOptimize(problem.criterion(x, nullptr));
}

void BM_Margins(benchmark::State& state) {
  Fixture f(kAnchors[0]);
  const planners::ExcitationProblem problem(f.model, f.options);
  const std::vector<double> x = problem.random_start(1);
  std::vector<double> jacobian;
  for (auto _ : state) benchmark::DoNotOptimize(problem.margins(x, state.range(0) ? &jacobian : nullptr));
  state.SetLabel(state.range(0) ? "with Jacobian" : "values");
}

}  // namespace

BENCHMARK(BM_ExcitationOptimisation)->DenseRange(0, 3)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_CriterionGradient)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Criterion)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Margins)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
