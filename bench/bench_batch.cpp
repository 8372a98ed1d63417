// csp_batch_bench: RNEA and the inertial regressor over N = 1024 states, the one-state algorithm in a
// loop against the batched form (dynamics/batch.hpp), per state.
//
// Model and states: csp_bench's (bench_model.hpp, bench_states.hpp), as one batch. The loop writes what the
// callers stack: a 7 x N torque matrix, a 7N x 70 regressor. Every iteration runs both forms on the
// same states, one after the other (process CPU time each), and the counters are the mean ns per
// state of each, one_state_ns and batched_ns, and their ratio one_state/batched: one run, one load.
#include <algorithm>
#include <cmath>
#include <ctime>

#include <benchmark/benchmark.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/batch.hpp"
#include "bench_model.hpp"

namespace {

using namespace csp;
using bench::model;

constexpr auto kStates = static_cast<Eigen::Index>(bench::kNumStates);

// csp_bench's states as one batch.
const StateBatch& batch() {
  static const StateBatch instance = [] {
    const bench::States& s = bench::states();
    StateBatch batch(kStates);
    for (Eigen::Index k = 0; k < kStates; ++k) {
      const auto index = static_cast<std::size_t>(k);
      batch.q.col(k) = s.q[index];
      batch.dq.col(k) = s.dq[index];
      batch.ddq.col(k) = s.ddq[index];
    }
    return batch;
  }();
  return instance;
}

void rnea_one_by_one(JointMatrix& tau) {
  const StateBatch& s = batch();
  Data data;
  tau.resize(kNumJoints, s.size());
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    Vector7 t;
    rnea(model(), data, s.q.col(k), s.dq.col(k), s.ddq.col(k), t);
    tau.col(k) = t;
  }
}

void regressor_one_by_one(Eigen::MatrixXd& Y) {
  const StateBatch& s = batch();
  const InertialRegressor regressor(model());
  Data data;
  Y.resize(kNumJoints * s.size(), kInertialParameters);
  for (Eigen::Index k = 0; k < s.size(); ++k)
    Y.middleRows<kNumJoints>(kNumJoints * k) = regressor(data, s.q.col(k), s.dq.col(k), s.ddq.col(k));
}

void rnea_batched(JointMatrix& tau) { rnea_batch(model(), batch(), tau); }
void regressor_batched(Eigen::MatrixXd& Y) { inertial_regressor_batch(model(), batch(), Y); }

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

void BM_RneaBatch(benchmark::State& state) { compare<JointMatrix>(state, rnea_one_by_one, rnea_batched); }
void BM_RegressorBatch(benchmark::State& state) { compare<Eigen::MatrixXd>(state, regressor_one_by_one, regressor_batched); }

BENCHMARK(BM_RneaBatch)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RegressorBatch)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
