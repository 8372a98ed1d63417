// The run (run/run.hpp): observers plugged into one run, whatever its command source (the
// scenario's built-in controller, the LCM bus, a recorded log; the CAN bus in tests/can_vcan).
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "bridge_support.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"
#include "support.hpp"

namespace csp::run {
namespace {

// Counts the states it sees; throws once it has seen `fail_at` of them (0: never), as a log whose
// disk filled up.
class CountingObserver : public Observer {
 public:
  explicit CountingObserver(long fail_at = 0) : fail_at_(fail_at) {}
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override {
    ++seen;
    last_time = state.time.toSec();
    if (seen == fail_at_) throw std::runtime_error("disk full");
  }
  long seen = 0;
  double last_time = 0.0;

 private:
  long fail_at_;
};

rt::Scenario short_scenario(double duration) {
  rt::Scenario scenario = rt::load_scenario(test::kDefaultScenario);
  scenario.duration = duration;
  return scenario;
}

// An observer that throws ends the motion as its duration would (no reflex), is not called again,
// and the observers after it see every cycle to the end.
TEST(RunObservers, AFailingObserverEndsTheRunAndTheOthersSeeItsEnd) {
  csp::run::Run run(short_scenario(0.5));
  CountingObserver before, failing(100), after;
  run.observe(before);
  run.observe(failing);
  run.observe(after);
  ControllerSource controller(run);
  const RunResult result = run.run(controller);
  EXPECT_EQ(result.observer_failure, "disk full");
  EXPECT_FALSE(controller.reflex()) << run.emulator().reflex_reason();
  EXPECT_FALSE(result.stopped);
  EXPECT_EQ(failing.seen, 100);
  EXPECT_EQ(before.seen, after.seen);
  EXPECT_GT(after.seen, 100) << "the motion closes with the next command";
  EXPECT_LT(after.seen, 110) << "and not at the scenario's duration (500 cycles)";
  EXPECT_EQ(controller.motion().timing.cycles, static_cast<uint64_t>(after.seen));
  EXPECT_EQ(run.emulator().state().robot_mode, rt::RobotMode::kIdle);
}

// The run's CSV log and tracking are those of the motion session it drives, row for row: a run adds
// no cycle and changes no state (logs stay bit-identical for a seed).
TEST(RunObservers, LogsTheStatesOfTheMotionSessionBitForBit) {
  const rt::Scenario scenario = short_scenario(0.3);
  const std::string ours = test::temp_path("run.csv"), reference = test::temp_path("run_reference.csv");
  {
    csp::run::Run run(scenario);
    CsvLogObserver log(ours, run.emulator());
    run.observe(log);
    ControllerSource controller(run);
    ASSERT_TRUE(run.run(controller).observer_failure.empty());
  }
  {
    rt::Emulator emulator(scenario.emulator);
    const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
    rt::CsvLog log(reference);
    log.write(emulator.state(), rt::CycleInfo{});
    rt::LoopOptions options;
    options.clock = scenario.clock;
    options.faults = scenario.command_faults;
    options.max_duration = scenario.duration;
    options.observer = [&](const rt::RobotState& state, const rt::CycleInfo& cycle) { log.write(state, cycle); };
    rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  }
  const std::string text = test::read_text(ours);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 302) << "header, the start state, 300 cycles";
  EXPECT_EQ(text, test::read_text(reference));
}

// Tracking against a reference: RMS and max of q - q_ref, by hand from the logged states.
TEST(RunObservers, TrackingMatchesTheErrorsOfTheStatesItSaw) {
  csp::run::Run run(short_scenario(0.2));
  const Vector7 offset = Vector7::Constant(0.01);
  const Vector7 start(run.emulator().state().q.data());
  const Vector7 target = start + offset;
  TrackingObserver tracking([&](double) -> Vector7 { return target; }, run.emulator());
  std::vector<Vector7> seen;
  class Recorder : public Observer {
   public:
    explicit Recorder(std::vector<Vector7>& q) : q_(q) {}
    void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override { q_.emplace_back(state.q.data()); }

   private:
    std::vector<Vector7>& q_;
  } recorder(seen);
  run.observe(tracking);
  run.observe(recorder);
  ControllerSource controller(run);
  run.run(controller);
  ASSERT_EQ(seen.size(), 200u);
  ASSERT_EQ(tracking.cycles(), 200);
  Vector7 squared = Vector7::Zero(), max = Vector7::Zero();
  for (const Vector7& q : seen) {
    const Vector7 error = (q - target).cwiseAbs();
    squared += error.cwiseAbs2();
    max = max.cwiseMax(error);
  }
  EXPECT_LT((tracking.rms_error() - (squared / 200.0).cwiseSqrt()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(tracking.max_error(), max);
  EXPECT_DOUBLE_EQ(tracking.last_time(), 0.2);
}

// A log replayed through a run is the recorded run again, state for state: the CSV log of the
// re-simulation (the server's side of each cycle: what it received) equals the CSV log the
// built-in controller's run wrote (the controller's side), and every recorded state compares
// bit-identical. Commands are lost on the way (5 %), so `command_received` is checked on both sides.
TEST(RunSources, AReplayedLogIsTheRecordedRunAgain) {
  rt::Scenario scenario = short_scenario(0.4);
  scenario.command_faults.loss_probability = 0.05;
  const std::string lcm_log = test::temp_path("run_replay.lcmlog");
  const std::string recorded = test::temp_path("run_recorded.csv"), replayed = test::temp_path("run_replayed.csv");
  {
    csp::run::Run run(scenario);
    ControllerSource controller(run);
    CsvLogObserver csv(recorded, run.emulator());
    LcmLogObserver lcm(lcm_log, run, controller.controller().mode);
    run.observe(csv);
    run.observe(lcm);
    ASSERT_TRUE(run.run(controller).observer_failure.empty());
    ASSERT_FALSE(controller.reflex()) << run.emulator().reflex_reason();
    ASSERT_GT(run.emulator().counters().lost_commands, 0u) << "the check needs lost commands";
  }
  const bridge::Recording recording(lcm_log);
  csp::run::Run run(recording.scenario);
  LogReplaySource replay(recording, {});
  CsvLogObserver csv(replayed, run.emulator());
  run.observe(csv);
  const RunResult result = run.run(replay);
  EXPECT_TRUE(result.observer_failure.empty());
  EXPECT_FALSE(result.stopped);
  EXPECT_TRUE(replay.report().identical()) << replay.report().first_difference;
  EXPECT_EQ(replay.report().states, 401u) << "the start state and 400 cycles";
  const std::string text = test::read_text(replayed);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 402) << "header, the start state, 400 cycles";
  EXPECT_EQ(text, test::read_text(recorded));
}

// The stop flag (a signal) ends a replay where it is: the states up to it are compared, the run
// says it was stopped, not that an observer failed.
TEST(RunSources, TheStopFlagEndsAReplayWhereItIs) {
  const rt::Scenario scenario = short_scenario(0.3);
  const std::string lcm_log = test::temp_path("run_stop.lcmlog");
  {
    csp::run::Run run(scenario);
    ControllerSource controller(run);
    LcmLogObserver lcm(lcm_log, run, controller.controller().mode);
    run.observe(lcm);
    run.run(controller);
  }
  const bridge::Recording recording(lcm_log);
  csp::run::Run run(recording.scenario);
  LogReplaySource replay(recording, {});
  std::atomic<bool> stop = false;
  class StopAt : public Observer {
   public:
    explicit StopAt(std::atomic<bool>& stop) : stop_(stop) {}
    void on_cycle(const rt::RobotState&, const rt::CycleInfo&) override {
      if (++seen == 100) stop_ = true;   // as the signal handler would
    }
    long seen = 0;

   private:
    std::atomic<bool>& stop_;
  } stop_at(stop);
  run.observe(stop_at);
  const RunResult result = run.run(replay, &stop);
  EXPECT_TRUE(result.stopped);
  EXPECT_TRUE(result.observer_failure.empty());
  EXPECT_EQ(stop_at.seen, 100);
  EXPECT_EQ(replay.report().states, 101u) << "the start state and the 100 cycles up to the stop";
  EXPECT_EQ(replay.report().differing_states, 0u);
}

// On the LCM bus: the observers see every cycle the server runs (no controller: idle cycles at the
// wall-clock pace), and one that fails ends the serve there; the serve's log stays whole and
// replays bit for bit.
TEST(RunSources, AnObserverOfAServeRunSeesEveryCycleAndCanEndIt) {
  const rt::Scenario scenario = rt::load_scenario(test::kDefaultScenario);
  const std::string log = test::temp_path("run_serve.lcmlog");
  bridge::ServeOptions options;
  options.duration = 1.0;
  options.lcm_url = test::unique_lcm_url(5);
  options.log_path = log;
  options.quiet = true;
  csp::run::Run run(scenario);
  LcmBusSource bus(options);
  CountingObserver counting, failing(200);
  run.observe(counting);
  run.observe(failing);
  const RunResult result = run.run(bus);
  EXPECT_EQ(result.observer_failure, "disk full");
  EXPECT_FALSE(result.stopped);
  EXPECT_EQ(bus.report().timing.cycles, 200u) << "ended at the failing cycle, not after 1000";
  EXPECT_EQ(counting.seen, 200);
  EXPECT_DOUBLE_EQ(counting.last_time, run.emulator().state().time.toSec());
  const bridge::ResimulationReport replay = bridge::resimulate(log);
  EXPECT_TRUE(replay.identical()) << replay.first_difference << replay.damage;
  EXPECT_EQ(replay.states, 201u);
}

}  // namespace
}  // namespace csp::run
