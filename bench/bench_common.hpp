// Shared by the CSP half (bench_csp.cpp, built like the library) and the KDL half
// (bench_kdl.cpp, built with the distribution KDL's Eigen alignment, see tests/kdl_peer.hpp).
// Only alignment-independent types cross between the two.
#pragma once

#include <benchmark/benchmark.h>

#include "bench_states.hpp"
#include "kdl_peer.hpp"

namespace csp::bench {

test::KdlPeer& kdl_peer();   // the benchmark model as a KDL chain

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
