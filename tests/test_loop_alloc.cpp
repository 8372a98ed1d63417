// No allocation in the 1 kHz loop: this executable replaces the global operator new with a
// counting one (its own binary, so that no other test pays for it), and checks that once the
// first cycles have run, a 10 s motion allocates nothing more, on both clocks.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <vector>

#include "contact_support.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/scenario.hpp"

namespace {
std::atomic<uint64_t> allocations{0};

void* counted_allocation(std::size_t size, std::size_t alignment) {
  ++allocations;
  void* p = nullptr;
  if (posix_memalign(&p, alignment, size ? size : 1) != 0) return nullptr;
  return p;
}
void* counted_or_throw(std::size_t size, std::size_t alignment) {
  if (void* p = counted_allocation(size, alignment)) return p;
  throw std::bad_alloc();
}
constexpr std::size_t kDefaultAlignment = __STDCPP_DEFAULT_NEW_ALIGNMENT__;
}  // namespace

void* operator new(std::size_t size) { return counted_or_throw(size, kDefaultAlignment); }
void* operator new[](std::size_t size) { return counted_or_throw(size, kDefaultAlignment); }
void* operator new(std::size_t size, std::align_val_t a) { return counted_or_throw(size, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t size, std::align_val_t a) { return counted_or_throw(size, static_cast<std::size_t>(a)); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return counted_allocation(size, kDefaultAlignment); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return counted_allocation(size, kDefaultAlignment); }
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_allocation(size, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_allocation(size, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace csp {
namespace {

constexpr uint64_t kWarmUpCycles = 10;   // the first cycles may size what they keep

rt::Scenario default_scenario() { return rt::load_scenario(rt::default_scenario_path()); }

struct Counted {
  uint64_t cycles = 0;
  uint64_t after_warm_up = 0;   // allocations from the end of the warm-up to the last cycle
  bool reflex = false;          // the motion ended in a reflex (its reason is a string, allocated)
  // Cycles from the duration's last one on that received no command: the command that closes the
  // motion came late (real time, a loaded machine), and the robot ran on until one arrived.
  uint64_t unanswered_at_end = 0;
};

// Runs the scenario's built-in controller for its duration and counts allocations between the
// observer calls of the warm-up's last cycle and the motion's last cycle. `extra` runs in the
// observer too (the check that the counter sees an allocation there).
Counted run_counted(const rt::Scenario& scenario, rt::Clock clock, const std::function<void()>& extra = {}) {
  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, {}, emulator);
  rt::LoopOptions options;
  options.clock = clock;
  options.faults = scenario.command_faults;
  options.max_duration = scenario.duration;
  Counted counted;
  uint64_t at_warm_up = 0, at_last = 0;
  const auto planned_cycles = static_cast<uint64_t>(std::llround(scenario.duration / rt::kDeltaT));
  options.observer = [&](const rt::RobotState&, const rt::CycleInfo& info) {
    if (extra) extra();
    if (++counted.cycles >= planned_cycles && !info.command_received) ++counted.unanswered_at_end;
    if (counted.cycles == kWarmUpCycles) at_warm_up = allocations.load();
    at_last = allocations.load();
  };
  const rt::MotionResult result = rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  if (clock == rt::Clock::kLockstep) {
    EXPECT_FALSE(result.reflex) << result.reason;
  }
  counted.after_warm_up = at_last - at_warm_up;
  counted.reflex = result.reflex;
  return counted;
}

// The counter sees an allocation made inside the loop: a record growing by one value per
// cycle, as the controller-timing record did.
TEST(LoopAllocation, CounterSeesAGrowingRecord) {
  rt::Scenario scenario = default_scenario();
  scenario.duration = 1.0;
  std::vector<double> record;
  const Counted counted = run_counted(scenario, rt::Clock::kLockstep, [&] { record.push_back(1.0); });
  EXPECT_GT(counted.after_warm_up, 0u);
}

TEST(LoopAllocation, LockstepTorqueMotionAllocatesNothing) {
  const rt::Scenario scenario = default_scenario();   // joint impedance, 10 s, a push at 6 s
  ASSERT_EQ(scenario.duration, 10.0);
  const Counted counted = run_counted(scenario, rt::Clock::kLockstep);
  EXPECT_EQ(counted.cycles, 10'000u);
  EXPECT_EQ(counted.after_warm_up, 0u);
}

TEST(LoopAllocation, LockstepJointPositionMotionAllocatesNothing) {
  rt::Scenario scenario = default_scenario();
  scenario.controller.type = "joint_position";   // the same excitation through the motion generator
  const Counted counted = run_counted(scenario, rt::Clock::kLockstep);
  EXPECT_EQ(counted.cycles, 10'000u);
  EXPECT_EQ(counted.after_warm_up, 0u);
}

// Commands lost at random and late ones (without the scenario's final burst: its reflex is an
// event that names its reason, not a cycle).
TEST(LoopAllocation, LockstepLossyNetworkAllocatesNothing) {
  rt::Scenario scenario = rt::load_scenario(std::string(CSP_SOURCE_DIR) + "/configs/scenarios/lossy_network.yaml");
  scenario.command_faults.bursts.clear();
  const Counted counted = run_counted(scenario, rt::Clock::kLockstep);
  EXPECT_EQ(counted.cycles, 6'000u);
  EXPECT_EQ(counted.after_warm_up, 0u);
}

// The real-time loop: the deadline clock and its statistics allocate nothing per cycle either. A
// loaded machine may stop the process for 20 ms, which ends the motion in a reflex whose reason is
// a new string (EmulatorRealtime.RunsAndReportsTiming): the test asks for one run without, in five.
TEST(LoopAllocation, RealtimeMotionAllocatesNothing) {
  rt::Scenario scenario = default_scenario();
  scenario.duration = 0.2;
  for (int attempt = 1; attempt <= 5; ++attempt) {
    const Counted counted = run_counted(scenario, rt::Clock::kRealtime);
    if (counted.reflex) continue;
    EXPECT_EQ(counted.cycles, 200u + counted.unanswered_at_end);   // 200 unless the closing command came late
    EXPECT_EQ(counted.after_warm_up, 0u);
    return;
  }
  ADD_FAILURE() << "five real-time runs of 200 ms each stalled for 20 ms or more";
}

// Emulator::step alone, in motion and idle.
TEST(LoopAllocation, EmulatorStepAllocatesNothing) {
  const rt::Scenario scenario = default_scenario();
  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, {}, emulator);
  emulator.start_motion(builtin.mode);
  rt::Command command = builtin.controller(emulator.state(), rt::Duration(0));
  emulator.step(&command);
  const uint64_t before = allocations.load();
  for (int k = 0; k < 10'000; ++k) {
    command = builtin.controller(emulator.state(), rt::Duration(1));
    emulator.step(&command);
  }
  ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  command.motion_finished = true;
  emulator.step(&command);
  ASSERT_FALSE(emulator.in_motion());
  for (int k = 0; k < 1'000; ++k) emulator.step(nullptr);   // idle
  EXPECT_EQ(allocations.load() - before, 0u);
}

// In contact with a scene (the probe pressing on the breathing abdomen: the contact query, the
// forces and the adaptive substeps run every substep).
TEST(LoopAllocation, EmulatorStepInContactAllocatesNothing) {
  rt::Emulator emulator(test::ultrasound_settings(default_scenario().emulator, true));
  test::PressingController controller(emulator.internal_model(), Vector3(0, 0, -10.0));
  emulator.start_motion(rt::ControlMode::kTorque);
  for (int k = 0; k < 2'000; ++k) {
    const rt::Command command = controller(emulator.state());
    emulator.step(&command);
  }
  ASSERT_GT(emulator.contact().active_contacts, 0);
  const uint64_t before = allocations.load();
  for (int k = 0; k < 5'000; ++k) {
    const rt::Command command = controller(emulator.state());
    emulator.step(&command);
  }
  ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  EXPECT_GT(emulator.contact().active_contacts, 0);
  EXPECT_EQ(allocations.load() - before, 0u);
}

}  // namespace
}  // namespace csp
