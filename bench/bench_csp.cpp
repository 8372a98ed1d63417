// csp_bench: every CSP algorithm next to its KDL twin (BM_<Quantity>_CSP / BM_<Quantity>_KDL).
//
// Model: Panda, Gaz et al. 2019 inertia, with the Franka Hand. 1024 seeded random states
// (q within the joint limits, |dq| <= 2.5 rad/s, |ddq| <= 10 rad/s^2, tau = rnea(q, dq, ddq)) are
// precomputed and cycled; the KDL half (bench_kdl.cpp) calls the KDL solvers directly on
// precomputed KDL::JntArray, so neither side pays for conversions.
// `/usr/bin/python3 bench/ratio_table.py` turns `csp_bench --benchmark_format=json` into a table.
//
//   Quantity           CSP                                 KDL twin
//   ForwardKinematics  forward_kinematics (7 joint         ChainFkSolverPos_recursive::JntToCart,
//                      frames, flange, EE, K, joint axes)  vector overload (all 8 segment tips)
//   Jacobian           forward_kinematics + zero_jacobian  ChainJntToJacSolver::JntToJac
//                      (CSP's Jacobian needs the FK)
//   FkJacobian         the same two calls (the FK yields   JntToCart(EE) + JntToJac
//                      the EE pose)
//   Rnea               rnea                                ChainIdSolver_RNE::CartToJnt
//   Gravity            gravity_torque                      ChainDynParam::JntToGravity
//   Coriolis           coriolis_torque (C(q,dq) dq)        ChainDynParam::JntToCoriolis
//   CoriolisMatrix     coriolis_matrix                     none: KDL has no Coriolis matrix
//   Regressor          InertialRegressor (7 x 70)          none: KDL has no inertial regressor
//   MassMatrix         crba                                ChainDynParam::JntToMass
//   ForwardDynamics    aba                                 ChainFdSolver_RNE::CartToJnt (KDL 1.5:
//                                                          JntToMass + RNE bias + LDL^T solve)
//   ForwardDynamicsCholesky  forward_dynamics_cholesky     the same ChainFdSolver_RNE (same method)
#include "bench_common.hpp"
#include "bench_model.hpp"
#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/regressor.hpp"

namespace csp::bench {
namespace {

// ---- Forward kinematics of all frames ---------------------------------------------------------

void BM_ForwardKinematics_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    forward_kinematics(model(), data, s.q[cycle()]);
    benchmark::DoNotOptimize(data.O_T_joint);
    benchmark::DoNotOptimize(data.O_T_K);
  }
}

// ---- EE Jacobian, EE pose + Jacobian ------------------------------------------------------------

void BM_Jacobian_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  Matrix6x7 J;
  StateCycle cycle;
  for (auto _ : state) {
    forward_kinematics(model(), data, s.q[cycle()]);
    zero_jacobian(data, Frame::kEndEffector, J);
    benchmark::DoNotOptimize(J);
  }
}

void BM_FkJacobian_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  Matrix6x7 J;
  StateCycle cycle;
  for (auto _ : state) {
    forward_kinematics(model(), data, s.q[cycle()]);
    zero_jacobian(data, Frame::kEndEffector, J);
    benchmark::DoNotOptimize(frame_pose(data, Frame::kEndEffector));
    benchmark::DoNotOptimize(J);
  }
}

// ---- Inverse dynamics ---------------------------------------------------------------------------

void BM_Rnea_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  Vector7 tau;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    rnea(model(), data, s.q[k], s.dq[k], s.ddq[k], tau);
    benchmark::DoNotOptimize(tau);
  }
}

void BM_Gravity_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  Vector7 g;
  StateCycle cycle;
  for (auto _ : state) {
    gravity_torque(model(), data, s.q[cycle()], g);
    benchmark::DoNotOptimize(g);
  }
}

void BM_Coriolis_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  Vector7 c;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    coriolis_torque(model(), data, s.q[k], s.dq[k], c);
    benchmark::DoNotOptimize(c);
  }
}

// No KDL twin: KDL computes C(q,dq) dq only.
void BM_CoriolisMatrix_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    coriolis_matrix(model(), data, s.q[k], s.dq[k]);
    benchmark::DoNotOptimize(data.coriolis_matrix);
  }
}

// No KDL twin: the 7 x 70 inertial regressor Y(q, dq, ddq) of the excitation design and the gap fits.
void BM_Regressor_CSP(benchmark::State& state) {
  const States& s = states();
  const InertialRegressor regressor(model());
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    InertialRegressorRows Y = regressor(data, s.q[k], s.dq[k], s.ddq[k]);
    benchmark::DoNotOptimize(Y);
  }
}

// ---- Mass matrix, forward dynamics --------------------------------------------------------------

void BM_MassMatrix_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    crba(model(), data, s.q[cycle()]);
    benchmark::DoNotOptimize(data.mass_matrix);
  }
}

void BM_ForwardDynamics_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    aba(model(), data, s.q[k], s.dq[k], s.tau[k]);
    benchmark::DoNotOptimize(data.ddq);
  }
}

void BM_ForwardDynamicsCholesky_CSP(benchmark::State& state) {
  const States& s = states();
  Data data;
  StateCycle cycle;
  for (auto _ : state) {
    const std::size_t k = cycle();
    forward_dynamics_cholesky(model(), data, s.q[k], s.dq[k], s.tau[k]);
    benchmark::DoNotOptimize(data.ddq);
  }
}

void register_benchmarks() {
  // Each CSP benchmark directly followed by its KDL twin.
  const struct {
    const char* name;
    void (*function)(benchmark::State&);
  } benchmarks[] = {
      {"BM_ForwardKinematics_CSP", BM_ForwardKinematics_CSP},
      {"BM_ForwardKinematics_KDL", BM_ForwardKinematics_KDL},
      {"BM_Jacobian_CSP", BM_Jacobian_CSP},
      {"BM_Jacobian_KDL", BM_Jacobian_KDL},
      {"BM_FkJacobian_CSP", BM_FkJacobian_CSP},
      {"BM_FkJacobian_KDL", BM_FkJacobian_KDL},
      {"BM_Rnea_CSP", BM_Rnea_CSP},
      {"BM_Rnea_KDL", BM_Rnea_KDL},
      {"BM_Gravity_CSP", BM_Gravity_CSP},
      {"BM_Gravity_KDL", BM_Gravity_KDL},
      {"BM_Coriolis_CSP", BM_Coriolis_CSP},
      {"BM_Coriolis_KDL", BM_Coriolis_KDL},
      {"BM_CoriolisMatrix_CSP", BM_CoriolisMatrix_CSP},
      {"BM_Regressor_CSP", BM_Regressor_CSP},
      {"BM_MassMatrix_CSP", BM_MassMatrix_CSP},
      {"BM_MassMatrix_KDL", BM_MassMatrix_KDL},
      {"BM_ForwardDynamics_CSP", BM_ForwardDynamics_CSP},
      {"BM_ForwardDynamicsCholesky_CSP", BM_ForwardDynamicsCholesky_CSP},
      {"BM_ForwardDynamics_KDL", BM_ForwardDynamics_KDL},
  };
  for (const auto& b : benchmarks) benchmark::RegisterBenchmark(b.name, b.function);
}

}  // namespace

test::KdlPeer& kdl_peer() {
  static test::KdlPeer instance(model());
  return instance;
}

}  // namespace csp::bench

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("csp_compiler", CSP_BENCH_COMPILER);
  benchmark::AddCustomContext("csp_build_type", CSP_BENCH_BUILD_TYPE);
  benchmark::AddCustomContext("csp_flags", CSP_BENCH_FLAGS);
  benchmark::AddCustomContext("kdl_version", CSP_BENCH_KDL_VERSION);
  benchmark::AddCustomContext("csp_model", "panda gaz2019 + hand");
  csp::bench::states();   // set up before any timing
  csp::bench::kdl_peer();
  csp::bench::register_benchmarks();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
