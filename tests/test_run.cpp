// The run (run/run.hpp): observers plugged into one run of a scenario's built-in controller.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "bridge_support.hpp"
#include "csp/run/observers.hpp"
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
  const RunResult result = run.run_builtin_controller();
  EXPECT_EQ(result.observer_failure, "disk full");
  EXPECT_FALSE(result.reflex()) << run.emulator().reflex_reason();
  EXPECT_FALSE(result.stopped);
  EXPECT_EQ(failing.seen, 100);
  EXPECT_EQ(before.seen, after.seen);
  EXPECT_GT(after.seen, 100) << "the motion closes with the next command";
  EXPECT_LT(after.seen, 110) << "and not at the scenario's duration (500 cycles)";
  EXPECT_EQ(result.motion.timing.cycles, static_cast<uint64_t>(after.seen));
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
    ASSERT_TRUE(run.run_builtin_controller().observer_failure.empty());
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
  run.run_builtin_controller();
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

}  // namespace
}  // namespace csp::run
