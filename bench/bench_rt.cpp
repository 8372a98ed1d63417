// csp_rt_bench: the emulator's lockstep throughput. One item = one 1 kHz cycle: the controller
// callback, the command path, the plant substeps, sensors and estimators, limit checks and the
// published RobotState. Target (issue 3): >= 200 000 cycles/s, i.e. <= 5 us per cycle.
#include <benchmark/benchmark.h>

#include "csp/rt/controllers.hpp"
#include "kdl_peer.hpp"

namespace {

using namespace csp;

// A lockstep motion of `cycles` cycles with the scenario's built-in controller, per iteration.
void run_scenario(benchmark::State& state, const std::string& controller_type) {
  rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  scenario.controller.type = controller_type;
  scenario.emulator.external_wrenches.clear();
  constexpr int kCycles = 2000;
  rt::LoopOptions options;
  options.max_duration = kCycles * rt::kDeltaT;
  for (auto _ : state) {
    state.PauseTiming();
    rt::Emulator emulator(scenario.emulator);
    const rt::BuiltinController builtin = rt::make_controller(scenario.controller, {}, emulator);
    state.ResumeTiming();
    const rt::MotionResult result = rt::run_motion(emulator, builtin.mode, builtin.controller, options);
    if (result.reflex) state.SkipWithError(result.reason.c_str());
    benchmark::DoNotOptimize(emulator.state().q);
  }
  state.SetItemsProcessed(state.iterations() * kCycles);
  state.counters["us_per_cycle"] = benchmark::Counter(
      static_cast<double>(state.iterations() * kCycles), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_LockstepCycle_JointImpedance(benchmark::State& state) { run_scenario(state, "joint_impedance"); }
void BM_LockstepCycle_JointPosition(benchmark::State& state) { run_scenario(state, "joint_position"); }
void BM_LockstepCycle_Float(benchmark::State& state) { run_scenario(state, "float"); }

// The emulator's own share: one step with a zero torque command, no controller. The robot's model
// is the plant's, so the gravity-compensated arm floats in place and every step does the full work
// (a drifting arm would end in a reflex and stand on its brakes).
void BM_EmulatorStep(benchmark::State& state) {
  rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  scenario.emulator.external_wrenches.clear();
  scenario.emulator.internal = scenario.emulator.plant;
  rt::Emulator emulator(scenario.emulator);
  emulator.start_motion(rt::ControlMode::kTorque);
  const rt::Command command{Vector7::Zero(), false};
  for (auto _ : state) emulator.step(&command);
  if (!emulator.in_motion()) state.SkipWithError(emulator.reflex_reason().c_str());
  state.SetItemsProcessed(state.iterations());
}

// Peer: the model computations of one emulator cycle done with KDL's solvers (two forward-dynamics
// substeps with friction, the gravity compensation, the expected torque by RNEA, the EE pose and
// Jacobian), without the emulator's bookkeeping. The twin of BM_EmulatorStep.
void BM_EmulatorStep_KDL(benchmark::State& state) {
  rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  const Model plant(scenario.emulator.plant);
  test::KdlPeer kdl(plant);
  Vector7 q = scenario.emulator.q_initial, dq = Vector7::Zero();
  const Vector7 tau = kdl.gravity(q);
  const double h = rt::kDeltaT / scenario.emulator.substeps;
  for (auto _ : state) {
    Vector7 gravity = kdl.gravity(q);
    for (int s = 0; s < scenario.emulator.substeps; ++s) {
      const Vector7 ddq = kdl.forward_dynamics(q, dq, tau - friction_torque(plant.parameters().friction, dq));
      dq += h * ddq;
      q += h * dq;
    }
    Vector7 expected = kdl.rnea(q, dq, Vector7::Zero());
    Matrix6x7 jacobian = kdl.ee_jacobian(q);
    Transform pose = kdl.ee_pose(q);
    benchmark::DoNotOptimize(gravity);
    benchmark::DoNotOptimize(expected);
    benchmark::DoNotOptimize(jacobian);
    benchmark::DoNotOptimize(pose);
    q = scenario.emulator.q_initial;   // stay at the same state, as the CSP twin does at rest
    dq.setZero();
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_LockstepCycle_JointImpedance)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LockstepCycle_JointPosition)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LockstepCycle_Float)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EmulatorStep)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmulatorStep_KDL)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
