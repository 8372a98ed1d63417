// The benchmarks' states, the same in csp_bench (both halves), csp_batch_bench and
// csp_pinocchio_bench: kNumStates seeded random states of the benchmark arm (bench_model.hpp), q
// within the joint limits, |dq| <= 2.5 rad/s, |ddq| <= 10 rad/s^2, tau = rnea(q, dq, ddq), computed
// once before any timing. Only alignment-independent types: the KDL half includes it too.
#pragma once

#include <cstddef>
#include <vector>

#include "csp/dynamics/model.hpp"

namespace csp::bench {

constexpr std::size_t kNumStates = 1024;   // a power of two: the state index is a mask
static_assert((kNumStates & (kNumStates - 1)) == 0);

struct States {
  std::vector<Vector7> q, dq, ddq, tau;   // tau = rnea(q, dq, ddq)
};
const States& states();   // bench_model.cpp

// Cycles through the precomputed states.
struct StateCycle {
  std::size_t next = 0;
  std::size_t operator()() { return next++ & (kNumStates - 1); }
};

}  // namespace csp::bench
