// csp_can_bench: the CAN path's cost per robot cycle (docs/can.md). One item = one full
// cyclic-synchronous-torque cycle of the seven joint drives on the in-memory path: 7 RPDO1 frames
// (controlword + target torque) in, SYNC in (latch, 402 state machine, one Arm cycle), 14 TPDOs
// out. Three figures: the protocol layer alone (a stand-in Arm returning a fixed state), the full
// cycle through the ServerArm and RobotServer (`csp can serve` without its sockets), and the
// emulator's step alone with the same kind of command. Target (issue 12): >= 20 000 cycles/s.
#include <benchmark/benchmark.h>

#include <cmath>

#include "csp/can/drive_bus.hpp"
#include "csp/can/server_arm.hpp"

namespace {

using namespace csp::can;
namespace rt = csp::rt;

class FixedArm : public Arm {
 public:
  ArmState state;
  ArmState cycle(const ArmCommand& command) override {
    state.joints[0].tau_J_d = command.joints[0].target_torque;
    return state;
  }
  ArmState measured() const override { return state; }
};

// A master on the in-memory bus: NMT start, the 402 walk, then one CST cycle per call.
class InMemoryMaster {
 public:
  explicit InMemoryMaster(Arm& arm) : bus(BusSettings{}, arm) {
    bus.receive(parse_frame("000#0100"));   // NMT start all
    for (int j = 0; j < kJoints; ++j) {
      rpdo[j].id = kRpdo1 + static_cast<uint32_t>(j + 1);
      rpdo[j].dlc = 4;
    }
    for (uint16_t cw : {0x06, 0x07, 0x0F}) cycle(cw, {});   // to operation enabled
  }
  void cycle(uint16_t controlword, const std::array<int16_t, kJoints>& torque) {
    for (int j = 0; j < kJoints; ++j) {
      put_le(rpdo[j].data.data(), 2, controlword);
      put_le(rpdo[j].data.data() + 2, 2, static_cast<uint16_t>(torque[j]));
      bus.receive(rpdo[j]);
    }
    bus.receive(sync);
  }
  DriveBus bus;
  std::array<Frame, kJoints> rpdo{};
  const Frame sync = parse_frame("080#");
};

void set_cycle_counters(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations());
  state.counters["ns_per_cycle"] = benchmark::Counter(static_cast<double>(state.iterations()) * 1e-9,
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_CstCycle7Joints(benchmark::State& state) {
  FixedArm arm;
  for (int j = 0; j < kJoints; ++j) arm.state.joints[j] = {0.1 * j, 0.1 * j, 0.01 * j, 1.0 + j, 0.5 * j, 0.05 * j};
  InMemoryMaster master(arm);
  if (master.bus.node(6).drive_state() != DriveState::kOperationEnabled) state.SkipWithError("drives not enabled");
  std::array<int16_t, kJoints> torque{};
  size_t frames_out = 0;
  for (auto _ : state) {
    master.bus.clear_sent();
    master.cycle(0x0F, torque);
    torque[0] = static_cast<int16_t>((torque[0] + 7) % 1000);
    frames_out = master.bus.sent().size();
    benchmark::DoNotOptimize(master.bus.sent().data());
  }
  if (frames_out != 2 * kJoints) state.SkipWithError("expected 14 TPDOs per cycle");
  set_cycle_counters(state);
}

// The master's torque: a joint impedance holding the start pose (libfranka's example gains), so
// that the arm stays well inside its limits however many cycles the benchmark runs.
template <typename State>
std::array<int16_t, kJoints> hold(const State& start, const State& now) {
  constexpr double K[kJoints] = {600, 600, 600, 600, 250, 150, 50}, D[kJoints] = {50, 50, 50, 20, 20, 20, 10};
  std::array<int16_t, kJoints> raw{};
  for (int j = 0; j < kJoints; ++j)
    raw[j] = static_cast<int16_t>(std::lround((K[j] * (start.q[j] - now.q[j]) - D[j] * now.dq[j]) / (j < 4 ? 3e-3 : 0.5e-3)));
  return raw;
}

void BM_CstCycleThroughRobotServer(benchmark::State& state) {
  const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  rt::Emulator robot(scenario.emulator);
  ServerArm arm(robot, scenario, "", [](const std::string&) {});
  InMemoryMaster master(arm);
  const rt::Emulator& emulator = arm.server().emulator();
  const rt::RobotState start = emulator.state();
  for (auto _ : state) {
    master.bus.clear_sent();
    master.cycle(0x0F, hold(start, emulator.state()));
  }
  if (!emulator.in_motion()) state.SkipWithError(("the motion ended: " + emulator.reflex_reason()).c_str());
  set_cycle_counters(state);
}

void BM_EmulatorStepAlone(benchmark::State& state) {
  rt::Emulator emulator(rt::load_scenario(rt::default_scenario_path()).emulator);
  emulator.start_motion(rt::ControlMode::kTorque);
  rt::Command command;
  const rt::RobotState start = emulator.state();
  for (auto _ : state) {
    const auto raw = hold(start, emulator.state());
    for (int j = 0; j < kJoints; ++j) command.values[j] = raw[j] * (j < 4 ? 3e-3 : 0.5e-3);
    emulator.step(&command);
  }
  if (!emulator.in_motion()) state.SkipWithError(("the motion ended: " + emulator.reflex_reason()).c_str());
  set_cycle_counters(state);
}

}  // namespace

BENCHMARK(BM_CstCycle7Joints)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_CstCycleThroughRobotServer)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EmulatorStepAlone)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
