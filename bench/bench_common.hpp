// Shared by the CSP half (bench_csp.cpp, built like the library) and the KDL half
// (bench_kdl.cpp, built with the distribution KDL's Eigen alignment, see tests/kdl_peer.hpp).
// Only alignment-independent types cross between the two.
#pragma once

#include <cstddef>
#include <vector>

#include <benchmark/benchmark.h>

#include "kdl_peer.hpp"

namespace csp::bench {

constexpr std::size_t kNumStates = 1024;   // a power of two: the state index is a mask
static_assert((kNumStates & (kNumStates - 1)) == 0);

// Seeded random states of the benchmark model, computed once before any timing.
struct States {
  std::vector<Vector7> q, dq, ddq, tau;   // tau = rnea(q, dq, ddq)
};
const States& states();
test::KdlPeer& kdl_peer();   // the benchmark model as a KDL chain

// Cycles through the precomputed states.
struct StateCycle {
  std::size_t next = 0;
  std::size_t operator()() { return next++ & (kNumStates - 1); }
};

// bench_kdl.cpp
void BM_ForwardKinematics_KDL(benchmark::State& state);
void BM_Jacobian_KDL(benchmark::State& state);
void BM_FkJacobian_KDL(benchmark::State& state);
void BM_Rnea_KDL(benchmark::State& state);
void BM_Gravity_KDL(benchmark::State& state);
void BM_Coriolis_KDL(benchmark::State& state);
void BM_MassMatrix_KDL(benchmark::State& state);
void BM_ForwardDynamics_KDL(benchmark::State& state);

}  // namespace csp::bench
