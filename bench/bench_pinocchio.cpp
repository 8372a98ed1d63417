// csp_pinocchio_bench: every CSP algorithm next to Pinocchio's, in one run on the same states
// (BM_<Quantity>_CSP / BM_<Quantity>_Pinocchio). Pinocchio is used header-only from a folder outside
// the tree (bench/README.md); it is no dependency of CSP.
//
// Model: Panda, Gaz et al. 2019 inertia, with the Franka Hand, as csp_bench. The Pinocchio model is
// built from the same csp::Model: joint i is a revolute-z joint placed at ^{i-1}T_i(q = 0) of the
// MDH table, carrying CSP's body i (end effector and load lumped on link 7), with the flange, EE and
// K frames on joint 7 and CSP's gravity and armature. Before any timing every quantity is compared
// on all states; the program stops if any differs by more than 1e-12 relative.
// csp_bench's model and states (bench_model.hpp, bench_states.hpp), also in Pinocchio's types, cycled.
// `/usr/bin/python3 bench/ratio_table.py` turns `--benchmark_format=json` into a table.
//
//   Quantity                 CSP                          Pinocchio
//   ForwardKinematics        forward_kinematics           forwardKinematics + updateFramePlacements
//                            (7 joints, flange, EE, K)    (7 joints; flange, EE, K frames)
//   FkJacobian               forward_kinematics +         computeFrameJacobian(EE, LOCAL_WORLD_ALIGNED)
//                            zero_jacobian(EE)            (the support's kinematics, EE pose and Jacobian)
//   Rnea                     rnea                         rnea
//   Gravity                  gravity_torque               computeGeneralizedGravity
//   Coriolis                 coriolis_torque (C dq)       nonLinearEffects of the model without gravity
//   CoriolisMatrix           coriolis_matrix              computeCoriolisMatrix
//   MassMatrix               crba (whole matrix)          crba (upper triangle, as Pinocchio leaves it)
//   ForwardDynamics          aba                          aba
//   ForwardDynamicsCholesky  forward_dynamics_cholesky    crba + nonLinearEffects + cholesky::decompose
//                                                         + cholesky::solve (Pinocchio's own factor)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/cholesky.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "bench_model.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp::bench {
namespace {

constexpr double kAgreement = 1e-12;       // largest relative difference accepted at start-up

// ---- The same arm as a Pinocchio model --------------------------------------------------------

pinocchio::SE3 to_se3(const Transform& transform) { return pinocchio::SE3(transform.rotation, transform.translation); }

// Pinocchio's dynamic parameters (m, h, I about the frame origin as xx xy yy xz yz zz) of a CSP body.
pinocchio::Inertia to_pinocchio(const SpatialInertia& body) {
  const Matrix3& I = body.rotational;
  Eigen::Matrix<double, 10, 1> parameters;
  parameters << body.mass, body.first_moment, I(0, 0), I(0, 1), I(1, 1), I(0, 2), I(1, 2), I(2, 2);
  return pinocchio::Inertia::FromDynamicParameters(parameters);
}

struct PinocchioArm {
  pinocchio::Model model;
  pinocchio::Model model_without_gravity;   // nonLinearEffects of it is C(q, dq) dq
  pinocchio::FrameIndex flange = 0, end_effector = 0, stiffness = 0;
};

const PinocchioArm& pinocchio_arm() {
  static const PinocchioArm instance = [] {
    const ModelParameters& p = model().parameters();
    PinocchioArm arm;
    pinocchio::JointIndex joint = 0;   // the universe
    for (int i = 0; i < kNumJoints; ++i) {
      // ^{i-1}T_i(q) = RotX(alpha) TransX(a) RotZ(theta_offset) TransZ(d) RotZ(q): the constant part
      // is the placement, RotZ(q) the joint.
      joint = arm.model.addJoint(joint, pinocchio::JointModelRZ(), to_se3(mdh_transform(p.joints[i], 0.0)),
                                 "joint" + std::to_string(i + 1));
      arm.model.appendBodyToJoint(joint, to_pinocchio(model().body(i)), pinocchio::SE3::Identity());
    }
    const Transform link7_T_EE = p.link7_T_flange * p.F_T_EE;
    arm.flange = arm.model.addFrame(pinocchio::Frame("flange", joint, to_se3(p.link7_T_flange), pinocchio::OP_FRAME));
    arm.end_effector = arm.model.addFrame(pinocchio::Frame("EE", joint, to_se3(link7_T_EE), pinocchio::OP_FRAME));
    const Transform link7_T_K = link7_T_EE * p.EE_T_K;
    arm.stiffness = arm.model.addFrame(pinocchio::Frame("K", joint, to_se3(link7_T_K), pinocchio::OP_FRAME));
    arm.model.gravity.linear(model().gravity());
    arm.model.armature = model().armature();
    arm.model_without_gravity = arm.model;
    arm.model_without_gravity.gravity.setZero();
    return arm;
  }();
  return instance;
}

// ---- States -------------------------------------------------------------------------------------

// csp_bench's states (bench_states.hpp) in Pinocchio's configuration/tangent type.
struct PinocchioStates {
  std::vector<Eigen::VectorXd> q, dq, ddq, tau;
};

const PinocchioStates& pinocchio_states() {
  static const PinocchioStates instance = [] {
    const States& s = states();
    PinocchioStates p;
    for (std::size_t k = 0; k < kNumStates; ++k) {
      p.q.emplace_back(s.q[k]);
      p.dq.emplace_back(s.dq[k]);
      p.ddq.emplace_back(s.ddq[k]);
      p.tau.emplace_back(s.tau[k]);
    }
    return p;
  }();
  return instance;
}

// The timed loop of every row: `compute(k)` evaluates the quantity at state k.
template <typename Compute>
void over_states(benchmark::State& state, Compute compute) {
  std::size_t next = 0;
  for (auto _ : state) compute(next++ & (kNumStates - 1));
}

// ---- Agreement, checked before any timing -------------------------------------------------------

// max |a - b| / max |b| over the entries.
double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

struct Agreement {
  const char* quantity;
  double worst = 0.0;   // largest relative difference over all states
};

enum Quantity { kForwardKinematics, kFkJacobian, kRnea, kGravity, kCoriolis, kCoriolisMatrix, kMassMatrix,
                kForwardDynamics, kForwardDynamicsCholesky };

// Every quantity of both libraries on every state; prints the worst differences, false if one is too large.
bool libraries_agree(std::vector<Agreement>& agreement) {
  const States& s = states();
  const PinocchioStates& ps = pinocchio_states();
  const PinocchioArm& arm = pinocchio_arm();
  Data data;
  pinocchio::Data pd(arm.model);
  Vector7 out;
  Matrix6x7 J;
  pinocchio::Data::Matrix6x pJ = pinocchio::Data::Matrix6x::Zero(6, arm.model.nv);
  agreement = {{"ForwardKinematics"}, {"FkJacobian"}, {"Rnea"}, {"Gravity"}, {"Coriolis"},
               {"CoriolisMatrix"}, {"MassMatrix"}, {"ForwardDynamics"}, {"ForwardDynamicsCholesky"}};
  auto record = [&agreement](Quantity quantity, double difference) {
    agreement[quantity].worst = std::max(agreement[quantity].worst, difference);
  };
  for (std::size_t k = 0; k < kNumStates; ++k) {
    const Eigen::VectorXd &q = ps.q[k], &dq = ps.dq[k], &tau = ps.tau[k];

    forward_kinematics(model(), data, s.q[k]);
    pinocchio::forwardKinematics(arm.model, pd, q);
    pinocchio::updateFramePlacements(arm.model, pd);
    auto record_pose = [&](const pinocchio::SE3& pose, const Transform& csp_pose) {
      record(kForwardKinematics, relative_difference(pose.toHomogeneousMatrix(), csp_pose.matrix()));
    };
    for (int i = 0; i < kNumJoints; ++i) record_pose(pd.oMi[i + 1], data.O_T_joint[i]);
    record_pose(pd.oMf[arm.flange], data.O_T_F);
    record_pose(pd.oMf[arm.end_effector], data.O_T_EE);
    record_pose(pd.oMf[arm.stiffness], data.O_T_K);

    zero_jacobian(data, Frame::kEndEffector, J);
    pinocchio::computeFrameJacobian(arm.model, pd, q, arm.end_effector, pinocchio::LOCAL_WORLD_ALIGNED, pJ);
    record(kFkJacobian, relative_difference(pJ, J));

    rnea(model(), data, s.q[k], s.dq[k], s.ddq[k], out);
    record(kRnea, relative_difference(pinocchio::rnea(arm.model, pd, q, dq, ps.ddq[k]), out));
    gravity_torque(model(), data, s.q[k], out);
    record(kGravity, relative_difference(pinocchio::computeGeneralizedGravity(arm.model, pd, q), out));
    coriolis_torque(model(), data, s.q[k], s.dq[k], out);
    record(kCoriolis, relative_difference(pinocchio::nonLinearEffects(arm.model_without_gravity, pd, q, dq), out));
    // The Coriolis matrix is not unique; both are the factorisation with dM/dt - 2C skew-symmetric.
    coriolis_matrix(model(), data, s.q[k], s.dq[k]);
    pinocchio::computeCoriolisMatrix(arm.model, pd, q, dq);
    record(kCoriolisMatrix, relative_difference(pd.C, data.coriolis_matrix));

    crba(model(), data, s.q[k]);
    pinocchio::crba(arm.model, pd, q);
    pd.M.triangularView<Eigen::StrictlyLower>() = pd.M.transpose().triangularView<Eigen::StrictlyLower>();
    record(kMassMatrix, relative_difference(pd.M, data.mass_matrix));

    aba(model(), data, s.q[k], s.dq[k], s.tau[k]);
    record(kForwardDynamics, relative_difference(pinocchio::aba(arm.model, pd, q, dq, tau), data.ddq));
    forward_dynamics_cholesky(model(), data, s.q[k], s.dq[k], s.tau[k]);
    pinocchio::crba(arm.model, pd, q);
    pinocchio::nonLinearEffects(arm.model, pd, q, dq);
    pinocchio::cholesky::decompose(arm.model, pd);
    Eigen::VectorXd ddq = tau - pd.nle;
    pinocchio::cholesky::solve(arm.model, pd, ddq);
    record(kForwardDynamicsCholesky, relative_difference(ddq, data.ddq));
  }
  bool agree = true;
  std::fprintf(stderr, "CSP vs Pinocchio, largest relative difference over %zu states (limit %.0e):\n", kNumStates,
               kAgreement);
  for (const Agreement& a : agreement) {
    std::fprintf(stderr, "  %-24s %.2e%s\n", a.quantity, a.worst, a.worst <= kAgreement ? "" : "  TOO LARGE");
    agree = agree && a.worst <= kAgreement;
  }
  return agree;
}

// ---- The rows -----------------------------------------------------------------------------------

void BM_ForwardKinematics_CSP(benchmark::State& state) {
  Data data;
  over_states(state, [&](std::size_t k) {
    forward_kinematics(model(), data, states().q[k]);
    benchmark::DoNotOptimize(data.O_T_joint);
    benchmark::DoNotOptimize(data.O_T_K);
  });
}

void BM_ForwardKinematics_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  over_states(state, [&](std::size_t k) {
    pinocchio::forwardKinematics(arm.model, pd, pinocchio_states().q[k]);
    pinocchio::updateFramePlacements(arm.model, pd);
    benchmark::DoNotOptimize(pd.oMi);
    benchmark::DoNotOptimize(pd.oMf);
  });
}

void BM_FkJacobian_CSP(benchmark::State& state) {
  Data data;
  Matrix6x7 J;
  over_states(state, [&](std::size_t k) {
    forward_kinematics(model(), data, states().q[k]);
    zero_jacobian(data, Frame::kEndEffector, J);
    benchmark::DoNotOptimize(frame_pose(data, Frame::kEndEffector));
    benchmark::DoNotOptimize(J);
  });
}

void BM_FkJacobian_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  pinocchio::Data::Matrix6x J = pinocchio::Data::Matrix6x::Zero(6, arm.model.nv);
  over_states(state, [&](std::size_t k) {
    pinocchio::computeFrameJacobian(arm.model, pd, pinocchio_states().q[k], arm.end_effector, pinocchio::LOCAL_WORLD_ALIGNED, J);
    benchmark::DoNotOptimize(pd.oMf[arm.end_effector]);
    benchmark::DoNotOptimize(J);
  });
}

void BM_Rnea_CSP(benchmark::State& state) {
  Data data;
  Vector7 tau;
  const States& s = states();
  over_states(state, [&](std::size_t k) {
    rnea(model(), data, s.q[k], s.dq[k], s.ddq[k], tau);
    benchmark::DoNotOptimize(tau);
  });
}

void BM_Rnea_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  const PinocchioStates& ps = pinocchio_states();
  over_states(state, [&](std::size_t k) {
    pinocchio::rnea(arm.model, pd, ps.q[k], ps.dq[k], ps.ddq[k]);
    benchmark::DoNotOptimize(pd.tau);
  });
}

void BM_Gravity_CSP(benchmark::State& state) {
  Data data;
  Vector7 g;
  over_states(state, [&](std::size_t k) {
    gravity_torque(model(), data, states().q[k], g);
    benchmark::DoNotOptimize(g);
  });
}

void BM_Gravity_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  over_states(state, [&](std::size_t k) {
    pinocchio::computeGeneralizedGravity(arm.model, pd, pinocchio_states().q[k]);
    benchmark::DoNotOptimize(pd.g);
  });
}

void BM_Coriolis_CSP(benchmark::State& state) {
  Data data;
  Vector7 c;
  over_states(state, [&](std::size_t k) {
    coriolis_torque(model(), data, states().q[k], states().dq[k], c);
    benchmark::DoNotOptimize(c);
  });
}

void BM_Coriolis_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model_without_gravity);
  over_states(state, [&](std::size_t k) {
    pinocchio::nonLinearEffects(arm.model_without_gravity, pd, pinocchio_states().q[k], pinocchio_states().dq[k]);
    benchmark::DoNotOptimize(pd.nle);
  });
}

void BM_CoriolisMatrix_CSP(benchmark::State& state) {
  Data data;
  over_states(state, [&](std::size_t k) {
    coriolis_matrix(model(), data, states().q[k], states().dq[k]);
    benchmark::DoNotOptimize(data.coriolis_matrix);
  });
}

void BM_CoriolisMatrix_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  over_states(state, [&](std::size_t k) {
    pinocchio::computeCoriolisMatrix(arm.model, pd, pinocchio_states().q[k], pinocchio_states().dq[k]);
    benchmark::DoNotOptimize(pd.C);
  });
}

void BM_MassMatrix_CSP(benchmark::State& state) {
  Data data;
  over_states(state, [&](std::size_t k) {
    crba(model(), data, states().q[k]);
    benchmark::DoNotOptimize(data.mass_matrix);
  });
}

void BM_MassMatrix_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  over_states(state, [&](std::size_t k) {
    pinocchio::crba(arm.model, pd, pinocchio_states().q[k]);
    benchmark::DoNotOptimize(pd.M);
  });
}

void BM_ForwardDynamics_CSP(benchmark::State& state) {
  Data data;
  const States& s = states();
  over_states(state, [&](std::size_t k) {
    aba(model(), data, s.q[k], s.dq[k], s.tau[k]);
    benchmark::DoNotOptimize(data.ddq);
  });
}

void BM_ForwardDynamics_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  const PinocchioStates& ps = pinocchio_states();
  over_states(state, [&](std::size_t k) {
    pinocchio::aba(arm.model, pd, ps.q[k], ps.dq[k], ps.tau[k]);
    benchmark::DoNotOptimize(pd.ddq);
  });
}

void BM_ForwardDynamicsCholesky_CSP(benchmark::State& state) {
  Data data;
  const States& s = states();
  over_states(state, [&](std::size_t k) {
    forward_dynamics_cholesky(model(), data, s.q[k], s.dq[k], s.tau[k]);
    benchmark::DoNotOptimize(data.ddq);
  });
}

void BM_ForwardDynamicsCholesky_Pinocchio(benchmark::State& state) {
  const PinocchioArm& arm = pinocchio_arm();
  pinocchio::Data pd(arm.model);
  Eigen::VectorXd ddq(arm.model.nv);
  const PinocchioStates& ps = pinocchio_states();
  over_states(state, [&](std::size_t k) {
    pinocchio::crba(arm.model, pd, ps.q[k]);
    pinocchio::nonLinearEffects(arm.model, pd, ps.q[k], ps.dq[k]);
    pinocchio::cholesky::decompose(arm.model, pd);
    ddq = ps.tau[k] - pd.nle;
    pinocchio::cholesky::solve(arm.model, pd, ddq);
    benchmark::DoNotOptimize(ddq);
  });
}

void register_benchmarks() {
  // Each CSP benchmark directly followed by its Pinocchio twin.
  const struct {
    const char* name;
    void (*function)(benchmark::State&);
  } benchmarks[] = {
      {"BM_ForwardKinematics_CSP", BM_ForwardKinematics_CSP},
      {"BM_ForwardKinematics_Pinocchio", BM_ForwardKinematics_Pinocchio},
      {"BM_FkJacobian_CSP", BM_FkJacobian_CSP},
      {"BM_FkJacobian_Pinocchio", BM_FkJacobian_Pinocchio},
      {"BM_Rnea_CSP", BM_Rnea_CSP},
      {"BM_Rnea_Pinocchio", BM_Rnea_Pinocchio},
      {"BM_Gravity_CSP", BM_Gravity_CSP},
      {"BM_Gravity_Pinocchio", BM_Gravity_Pinocchio},
      {"BM_Coriolis_CSP", BM_Coriolis_CSP},
      {"BM_Coriolis_Pinocchio", BM_Coriolis_Pinocchio},
      {"BM_CoriolisMatrix_CSP", BM_CoriolisMatrix_CSP},
      {"BM_CoriolisMatrix_Pinocchio", BM_CoriolisMatrix_Pinocchio},
      {"BM_MassMatrix_CSP", BM_MassMatrix_CSP},
      {"BM_MassMatrix_Pinocchio", BM_MassMatrix_Pinocchio},
      {"BM_ForwardDynamics_CSP", BM_ForwardDynamics_CSP},
      {"BM_ForwardDynamics_Pinocchio", BM_ForwardDynamics_Pinocchio},
      {"BM_ForwardDynamicsCholesky_CSP", BM_ForwardDynamicsCholesky_CSP},
      {"BM_ForwardDynamicsCholesky_Pinocchio", BM_ForwardDynamicsCholesky_Pinocchio},
  };
  for (const auto& b : benchmarks) benchmark::RegisterBenchmark(b.name, b.function);
}

}  // namespace
}  // namespace csp::bench

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  std::vector<csp::bench::Agreement> agreement;
  if (!csp::bench::libraries_agree(agreement)) {
    std::fprintf(stderr, "CSP and Pinocchio disagree: not a side-by-side of the same arm, nothing timed\n");
    return EXIT_FAILURE;
  }
  benchmark::AddCustomContext("csp_compiler", CSP_BENCH_COMPILER);
  benchmark::AddCustomContext("csp_build_type", CSP_BENCH_BUILD_TYPE);
  benchmark::AddCustomContext("csp_flags", CSP_BENCH_FLAGS);
  benchmark::AddCustomContext("pinocchio_version", PINOCCHIO_VERSION);
  benchmark::AddCustomContext("csp_model", "panda gaz2019 + hand");
  for (const csp::bench::Agreement& a : agreement) {
    char worst[32];
    std::snprintf(worst, sizeof worst, "%.2e", a.worst);
    benchmark::AddCustomContext(std::string("agreement_") + a.quantity, worst);
  }
  csp::bench::register_benchmarks();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
