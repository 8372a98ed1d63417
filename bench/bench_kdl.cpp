// The KDL twins (see bench_csp.cpp). KDL side: Eigen with the distribution KDL's alignment,
// before any include (tests/kdl_peer.hpp explains why).
#define EIGEN_MAX_ALIGN_BYTES 16
#define EIGEN_MALLOC_ALREADY_ALIGNED 1
#define CSP_KDL_SIDE
#include <stdexcept>
#include <string>

#include "bench_common.hpp"

namespace csp::bench {
namespace {

// The states as KDL joint arrays, converted once (on first use, outside the timed loops).
struct KdlStates {
  KdlStates() {
    const States& s = states();
    for (std::size_t k = 0; k < kNumStates; ++k) {
      q.push_back(test::to_kdl(s.q[k]));
      dq.push_back(test::to_kdl(s.dq[k]));
      ddq.push_back(test::to_kdl(s.ddq[k]));
      tau.push_back(test::to_kdl(s.tau[k]));
    }
  }
  std::vector<KDL::JntArray> q, dq, ddq, tau;
};

const KdlStates& kdl_states() {
  static const KdlStates instance;
  return instance;
}

test::KdlPeer::Kdl& kdl() { return kdl_peer().kdl(); }

void check(int kdl_error) {
  if (kdl_error < 0) throw std::runtime_error("KDL solver error " + std::to_string(kdl_error));
}

}  // namespace

// All segment tips (7 links + EE) in one call.
void BM_ForwardKinematics_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainFkSolverPos_recursive& fk = kdl().fk;
  std::vector<KDL::Frame> frames(kdl().chain.getNrOfSegments());
  StateCycle cycle;
  for (auto _ : state) {
    check(fk.JntToCart(s.q[cycle()], frames));
    benchmark::DoNotOptimize(frames.data());
    benchmark::ClobberMemory();
  }
}

void BM_Jacobian_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainJntToJacSolver& solver = kdl().jacobian;
  KDL::Jacobian J(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    check(solver.JntToJac(s.q[cycle()], J));
    benchmark::DoNotOptimize(J.data.data());
    benchmark::ClobberMemory();
  }
}

void BM_FkJacobian_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainFkSolverPos_recursive& fk = kdl().fk;
  KDL::ChainJntToJacSolver& solver = kdl().jacobian;
  KDL::Frame pose;
  KDL::Jacobian J(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    const KDL::JntArray& q = s.q[cycle()];
    check(fk.JntToCart(q, pose));
    check(solver.JntToJac(q, J));
    benchmark::DoNotOptimize(pose);
    benchmark::DoNotOptimize(J.data.data());
    benchmark::ClobberMemory();
  }
}

void BM_Rnea_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainIdSolver_RNE& solver = kdl().id;
  const KDL::Wrenches& no_wrenches = kdl().no_wrenches;
  KDL::JntArray tau(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    check(solver.CartToJnt(s.q[k], s.dq[k], s.ddq[k], no_wrenches, tau));
    benchmark::DoNotOptimize(tau.data.data());
    benchmark::ClobberMemory();
  }
}

void BM_Gravity_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainDynParam& dyn = kdl().dyn;
  KDL::JntArray g(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    check(dyn.JntToGravity(s.q[cycle()], g));
    benchmark::DoNotOptimize(g.data.data());
    benchmark::ClobberMemory();
  }
}

void BM_Coriolis_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainDynParam& dyn = kdl().dyn;
  KDL::JntArray c(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    check(dyn.JntToCoriolis(s.q[k], s.dq[k], c));
    benchmark::DoNotOptimize(c.data.data());
    benchmark::ClobberMemory();
  }
}

void BM_MassMatrix_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainDynParam& dyn = kdl().dyn;
  KDL::JntSpaceInertiaMatrix M(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    check(dyn.JntToMass(s.q[cycle()], M));
    benchmark::DoNotOptimize(M.data.data());
    benchmark::ClobberMemory();
  }
}

// KDL 1.5 has ChainFdSolver_RNE: JntToMass + RNE with zero acceleration + LDL^T solve.
void BM_ForwardDynamics_KDL(benchmark::State& state) {
  const KdlStates& s = kdl_states();
  KDL::ChainFdSolver& solver = *kdl().fd;   // a ChainFdSolver_RNE
  const KDL::Wrenches& no_wrenches = kdl().no_wrenches;
  KDL::JntArray ddq(kNumJoints);
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    check(solver.CartToJnt(s.q[k], s.dq[k], s.tau[k], no_wrenches, ddq));
    benchmark::DoNotOptimize(ddq.data.data());
    benchmark::ClobberMemory();
  }
}

}  // namespace csp::bench
