// csp_can_bench: the CAN protocol layer's cost per robot cycle (docs/can.md). One item = one full
// cyclic-synchronous-torque cycle of the seven joint drives on the in-memory path: 7 RPDO1 frames
// (controlword + target torque) in, SYNC in (latch, 402 state machine, one Arm cycle), 14 TPDOs
// out. The Arm is a stand-in returning a fixed state, so this is the protocol layer alone, without
// the emulator's step (csp_rt_bench measures that). Target (issue 12): >= 20 000 cycles/s.
#include <benchmark/benchmark.h>

#include "csp/can/drive_bus.hpp"

namespace {

using namespace csp::can;

class FixedArm : public Arm {
 public:
  ArmState state;
  ArmState cycle(const ArmCommand& command) override {
    state.joints[0].tau_J_d = command.joints[0].target_torque;
    return state;
  }
};

void BM_CstCycle7Joints(benchmark::State& state) {
  FixedArm arm;
  for (int j = 0; j < kJoints; ++j) arm.state.joints[j] = {0.1 * j, 0.01 * j, 1.0 + j, 0.5 * j, 0.05 * j};
  DriveBus bus(BusSettings{}, arm);
  bus.receive(parse_frame("000#0100"));   // NMT start all
  std::array<Frame, kJoints> rpdo{};
  for (int j = 0; j < kJoints; ++j) {
    rpdo[j].id = kRpdo1 + static_cast<uint32_t>(j + 1);
    rpdo[j].dlc = 4;
  }
  const Frame sync = parse_frame("080#");
  auto cycle = [&](uint16_t controlword, int16_t torque) {
    for (Frame& f : rpdo) {
      put_le(f.data.data(), 2, controlword);
      put_le(f.data.data() + 2, 2, static_cast<uint16_t>(torque));
      bus.receive(f);
    }
    bus.receive(sync);
  };
  for (uint16_t cw : {0x06, 0x07, 0x0F}) cycle(cw, 0);   // to operation enabled
  if (bus.node(6).drive_state() != DriveState::kOperationEnabled) state.SkipWithError("drives not enabled");
  int16_t torque = 0;
  size_t frames_out = 0;
  for (auto _ : state) {
    bus.clear_sent();
    cycle(0x0F, torque);
    torque = static_cast<int16_t>((torque + 7) % 1000);
    frames_out = bus.sent().size();
    benchmark::DoNotOptimize(bus.sent().data());
  }
  if (frames_out != 2 * kJoints) state.SkipWithError("expected 14 TPDOs per cycle");
  state.SetItemsProcessed(state.iterations());
  state.counters["ns_per_cycle"] = benchmark::Counter(static_cast<double>(state.iterations()) * 1e-9,
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_CstCycle7Joints)->Unit(benchmark::kNanosecond);

BENCHMARK_MAIN();
