// csp_view_bench: the 1 kHz cycle with and without a live view attached, side by side in one run
// (docs/view.md, "Live"). One item = one emulator step and the run's observer call; with a view, a
// page is connected (civetweb's WebSocket client) and receives every frame the sender makes. The
// view must not slow the cycle: compare the rows' ns per cycle (ratio_table.py prints the ratios).
#include <civetweb.h>

#include <chrono>
#include <thread>

#include <benchmark/benchmark.h>

#include "csp/view/inputs.hpp"
#include "csp/view/live_view.hpp"

namespace {

using namespace csp;

int discard(mg_connection*, int, char*, std::size_t, void*) { return 1; }

// `frames_per_second` 0: no view; else a LiveView at that rate with one page attached.
void BM_CycleWithLiveView(benchmark::State& state) {
  const double frames_per_second = static_cast<double>(state.range(0));
  rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  scenario.emulator.external_wrenches.clear();
  scenario.emulator.internal = scenario.emulator.plant;   // floats in place: every step does the full work
  rt::Emulator emulator(scenario.emulator);
  emulator.start_motion(rt::ControlMode::kTorque);
  const rt::Command command{Vector7::Zero(), false};
  const rt::CycleInfo cycle{};

  std::unique_ptr<view::ViewServer> server;
  std::unique_ptr<view::LiveView> live;
  mg_connection* page = nullptr;
  if (frames_per_second > 0) {
    server = std::make_unique<view::ViewServer>("127.0.0.1", 0, nlohmann::json::object());
    live = std::make_unique<view::LiveView>(*server, view::view_robot(scenario), frames_per_second);
    char error[256] = "";
    const int port = std::stoi(server->url().substr(server->url().rfind(':') + 1));
    page = mg_connect_websocket_client("127.0.0.1", port, 0, error, sizeof error, "/api/live", nullptr, discard, nullptr, nullptr);
    if (page == nullptr) {
      state.SkipWithError(error);
      return;
    }
    while (server->pages() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (auto _ : state) {
    emulator.step(&command);
    if (live) live->on_cycle(emulator.state(), cycle);
  }
  if (!emulator.in_motion()) state.SkipWithError(emulator.reflex_reason().c_str());
  state.SetItemsProcessed(state.iterations());
  if (live) {
    state.counters["frames_sent"] = static_cast<double>(live->frames_sent());
    live.reset();
    mg_close_connection(page);
  }
}
BENCHMARK(BM_CycleWithLiveView)->Arg(0)->Arg(30)->Arg(1000)->Unit(benchmark::kMicrosecond)->MinTime(2.0)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
