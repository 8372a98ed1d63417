// One run of a scenario's robot: the scenario, the emulated robot, a command source and the
// observers that watch it (docs/architecture.md, "A run"). The cycles are paced and timed by
// rt::CycleDriver inside each source, the same for every front end.
//
// Command sources plug in (sources.hpp): the scenario's controller in this process, the LCM bus,
// the CAN bus, a recorded log. Observers plug in: each sees every state the robot publishes and
// what its cycle received, in order (rt/observers and run/observers.hpp: the CSV and LCM logs,
// tracking, medical metrics, clearance, progress). An observer that throws (a log whose disk is
// full) ends the run as a signal would: what was written stays whole, and the error is reported;
// the other observers see the run to its end.
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::run {

class Observer {
 public:
  virtual ~Observer() = default;
  // After every cycle, with the state the robot published.
  virtual void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) = 0;
};

// Where a run's commands come from (like OMPL's StateValidityChecker, one method to implement).
class CommandSource {
 public:
  virtual ~CommandSource() = default;
  // Runs `robot` (built from `scenario`) cycle by cycle until the source ends (its duration, its
  // log's end) or `stop` is set, and calls `after_cycle` after each cycle. Throws what its
  // transport throws (a bus that cannot be opened); the source keeps its own report.
  virtual void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
                     const std::atomic<bool>& stop) = 0;
};

struct RunResult {
  std::string observer_failure;   // the first observer that threw: what it said
  bool stopped = false;           // ended early by the stop flag (a signal)
};

class Run {
 public:
  explicit Run(const rt::Scenario& scenario) : scenario_(scenario), emulator_(scenario_.emulator) {}

  const rt::Scenario& scenario() const { return scenario_; }
  const rt::Emulator& emulator() const { return emulator_; }

  // Observers are called in the order they were added; the run does not own them.
  void observe(Observer& observer) { observers_.push_back(&observer); }

  // Runs the robot with `source`'s commands. `stop` (may be null; a signal handler sets it) ends
  // the run where it is; the run sets it too when an observer fails. A run runs once.
  RunResult run(CommandSource& source, std::atomic<bool>* stop = nullptr);

 private:
  rt::Scenario scenario_;
  rt::Emulator emulator_;
  std::vector<Observer*> observers_;
};

}  // namespace csp::run
