// csp_contact_bench: the emulator's cycle with the ultrasound probe pressing 10 N on the breathing
// abdomen (contact query, forces, the implicit damping and friction step and adaptive substeps in
// every substep) side by side with the same arm, controller and pose without a scene; and one
// contact query alone. Target (issue 14):
// >= 100 000 lockstep cycles/s with contact, i.e. <= 10 us per cycle (docs/contact.md).
#include <benchmark/benchmark.h>

#include "contact_support.hpp"
#include "csp/rt/scenario.hpp"

namespace {

using namespace csp;

rt::EmulatorSettings base_settings() {
  rt::EmulatorSettings s = rt::load_scenario(rt::default_scenario_path()).emulator;
  s.internal = s.plant;   // no drift from model mismatch: the cost alone
  return s;
}

// One item = one 1 kHz cycle (controller, step), after 2 s of pressing (in contact when `contact`).
void run_pressing(benchmark::State& state, bool contact, double friction_velocity = rt::ContactOptions{}.friction_velocity) {
  rt::EmulatorSettings settings = test::ultrasound_settings(base_settings(), contact);
  settings.contact.friction_velocity = friction_velocity;
  rt::Emulator emulator(settings);
  test::PressingController controller(emulator.internal_model(), Vector3(0, 0, contact ? -10.0 : 0.0));
  emulator.start_motion(rt::ControlMode::kTorque);
  for (int k = 0; k < 2000; ++k) {
    const rt::Command command = controller(emulator.state());
    emulator.step(&command);
  }
  if (contact && emulator.contact().active_contacts == 0) state.SkipWithError("the probe does not touch the abdomen");
  // The probe creeps over the curved abdomen: every 5 s back to the pressing state of t = 2 s.
  const rt::Emulator pressing = emulator;
  int cycles = 0;
  for (auto _ : state) {
    if (++cycles % 5000 == 0) {
      state.PauseTiming();
      emulator = pressing;
      state.ResumeTiming();
    }
    const rt::Command command = controller(emulator.state());
    emulator.step(&command);
  }
  if (!emulator.in_motion()) state.SkipWithError(emulator.reflex_reason().c_str());
  state.SetItemsProcessed(state.iterations());
  state.counters["substeps"] = emulator.contact().substeps;
  state.counters["newton"] = emulator.contact().newton_iterations;
  state.counters["us_per_cycle"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_CycleInContact(benchmark::State& state) { run_pressing(state, true); }
void BM_CycleWithoutScene(benchmark::State& state) { run_pressing(state, false); }
// The friction's slope mu F_n / v_s no longer sets the substeps (its step is implicit,
// docs/contact.md): v_s = 1 cm/s costs what the default 1 mm/s does.
void BM_CycleInContact_FrictionVelocity10mm(benchmark::State& state) { run_pressing(state, true, 0.01); }

// One substep's contact query: place the arm's and the probe's capsules, broad and narrow phase
// against the scene's obstacles, the forces of the touching pair, at a pressing state.
void BM_ContactQuery(benchmark::State& state) {
  const rt::EmulatorSettings settings = test::ultrasound_settings(base_settings(), true);
  rt::Emulator emulator(settings);
  test::PressingController controller(emulator.internal_model(), Vector3(0, 0, -10.0));
  emulator.start_motion(rt::ControlMode::kTorque);
  for (int k = 0; k < 2000; ++k) {
    const rt::Command command = controller(emulator.state());
    emulator.step(&command);
  }
  rt::SceneContact query(settings.scene, settings.contact);
  rt::ContactState contact = query.initial_state();
  const Vector7 q(emulator.state().q.data()), dq(emulator.state().dq.data());
  Data data;
  double t = 2.0;
  for (auto _ : state) {
    query.evaluate(emulator.plant_model(), data, t, q, dq, contact);
    benchmark::DoNotOptimize(contact.link_wrenches);
    t += 1e-4;
  }
  if (contact.active_contacts == 0) state.SkipWithError("the probe does not touch the abdomen");
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(BM_CycleInContact)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CycleWithoutScene)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CycleInContact_FrictionVelocity10mm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ContactQuery)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
