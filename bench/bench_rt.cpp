// csp_rt_bench: the emulator's lockstep throughput. One item = one 1 kHz cycle: the controller
// callback, the command path, the plant substeps, sensors and estimators, limit checks and the
// published RobotState. Target (issue 3): >= 200 000 cycles/s, i.e. <= 5 us per cycle.
#include <benchmark/benchmark.h>

#include "csp/rt/controllers.hpp"

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

// The emulator's own share: one step with a fixed torque command, no controller.
void BM_EmulatorStep(benchmark::State& state) {
  rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  scenario.emulator.external_wrenches.clear();
  rt::Emulator emulator(scenario.emulator);
  emulator.start_motion(rt::ControlMode::kTorque);
  const rt::Command command{Vector7::Zero(), false};
  for (auto _ : state) emulator.step(&command);
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_LockstepCycle_JointImpedance)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LockstepCycle_JointPosition)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LockstepCycle_Float)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EmulatorStep)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
