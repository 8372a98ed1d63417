// csp_batch_bench: RNEA and the inertial regressor over N = 1000 states, the one-state algorithm in a
// loop against the batched form (dynamics/batch.hpp), per state.
//
// Model: Panda, Gaz et al. 2019 inertia, with the Franka Hand (as csp_bench). Seeded random states
// (q within the joint limits, |dq| <= 2.5 rad/s, |ddq| <= 10 rad/s^2). The loop writes what the
// callers stack: a 7 x N torque matrix, a 7N x 70 regressor. Every iteration runs both forms on the
// same states, one after the other (process CPU time each), and the counters are the mean ns per
// state of each, one_state_ns and batched_ns, and their ratio one_state/batched: one run, one load.
#include <algorithm>
#include <cmath>
#include <ctime>
#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/batch.hpp"
#include "csp/io/robot_config.hpp"

namespace {

using namespace csp;

constexpr Eigen::Index kStates = 1000;

const Model& model() {
  static const Model instance = [] {
    ModelOptions options;
    options.inertia = "gaz2019";
    options.end_effector = "hand";
    return Model(model_parameters(load_robot_config(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"), options));
  }();
  return instance;
}

const StateBatch& states() {
  static const StateBatch instance = [] {
    std::mt19937_64 engine(2029);
    const JointLimits& limits = model().parameters().joint_limits;
    StateBatch batch(kStates);
    for (Eigen::Index k = 0; k < kStates; ++k)
      for (int i = 0; i < kNumJoints; ++i) {
        batch.q(i, k) = std::uniform_real_distribution<double>(limits.q_min[i], limits.q_max[i])(engine);
        batch.dq(i, k) = std::uniform_real_distribution<double>(-2.5, 2.5)(engine);
        batch.ddq(i, k) = std::uniform_real_distribution<double>(-10.0, 10.0)(engine);
      }
    return batch;
  }();
  return instance;
}

void rnea_one_by_one(JointMatrix& tau) {
  const StateBatch& s = states();
  Data data;
  tau.resize(kNumJoints, s.size());
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    Vector7 t;
    rnea(model(), data, s.q.col(k), s.dq.col(k), s.ddq.col(k), t);
    tau.col(k) = t;
  }
}

void regressor_one_by_one(Eigen::MatrixXd& Y) {
  const StateBatch& s = states();
  const InertialRegressor regressor(model());
  Data data;
  Y.resize(kNumJoints * s.size(), kInertialParameters);
  for (Eigen::Index k = 0; k < s.size(); ++k)
    Y.middleRows<kNumJoints>(kNumJoints * k) = regressor(data, s.q.col(k), s.dq.col(k), s.ddq.col(k));
}

void rnea_batched(JointMatrix& tau) { rnea_batch(model(), states(), tau); }
void regressor_batched(Eigen::MatrixXd& Y) { inertial_regressor_batch(model(), states(), Y); }

// CPU time of this process: the machine is shared, and wall time counts the other programs' turns.
double cpu_ns() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return 1e9 * static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec);
}

template <typename Output>
double ns_per_state(void (*form)(Output&), Output& out) {
  const double start = cpu_ns();
  form(out);
  benchmark::DoNotOptimize(out.data());
  return (cpu_ns() - start) / kStates;
}

// Both forms on the same states, alternately in every iteration, so that they share the load.
template <typename Output>
void compare(benchmark::State& state, void (*one_state)(Output&), void (*batched)(Output&)) {
  Output out;
  double one_state_ns = 0.0, batched_ns = 0.0;
  for (auto _ : state) {
    one_state_ns += ns_per_state(one_state, out);
    batched_ns += ns_per_state(batched, out);
  }
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["one_state_ns"] = one_state_ns / iterations;
  state.counters["batched_ns"] = batched_ns / iterations;
  state.counters["one_state/batched"] = one_state_ns / batched_ns;
}

void BM_Rnea1000(benchmark::State& state) { compare<JointMatrix>(state, rnea_one_by_one, rnea_batched); }
void BM_Regressor1000(benchmark::State& state) { compare<Eigen::MatrixXd>(state, regressor_one_by_one, regressor_batched); }

BENCHMARK(BM_Rnea1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Regressor1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
