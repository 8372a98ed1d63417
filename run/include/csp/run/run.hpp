// One run of a scenario's robot: the scenario, the emulated robot, a command source and the
// observers that watch it (docs/architecture.md, "A run"). The cycles are paced and timed by
// rt::CycleDriver, the same for every front end.
//
// Observers plug in: each sees every state the robot publishes and what its cycle received, in
// order (rt/observers and run/observers.hpp: the CSV and LCM logs, tracking, medical metrics,
// clearance, progress). An observer that throws (a log whose disk is full) ends the run as its
// duration would: the robot holds, what was written stays whole, and the error is reported; the
// other observers see the run to its end.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "csp/rt/control_loop.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::run {

class Observer {
 public:
  virtual ~Observer() = default;
  // After every cycle, with the state the robot published.
  virtual void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) = 0;
};

struct RunResult {
  rt::MotionResult motion;         // reflex, errors and the timing report
  std::string controller_failure;  // the controller threw: what it said (the robot is in Reflex)
  std::string observer_failure;    // the first observer that threw: what it said
  bool stopped = false;            // ended early by the stop flag (a signal)
  bool reflex() const { return motion.reflex || !controller_failure.empty(); }
};

class Run {
 public:
  explicit Run(const rt::Scenario& scenario);

  const rt::Scenario& scenario() const { return scenario_; }
  const rt::Emulator& emulator() const { return emulator_; }
  // The scenario's built-in controller, made for this run's robot (its mode, a medical status).
  const rt::BuiltinController& controller() const { return controller_; }

  // Observers are called in the order they were added; the run does not own them.
  void observe(Observer& observer) { observers_.push_back(&observer); }

  // The scenario's built-in controller in this process, on the scenario's clock, with its command
  // faults, for its duration (`csp emulate`, `csp plan --verify`). `stop` (may be null) ends the
  // motion as its duration would.
  RunResult run_builtin_controller(const std::atomic<bool>* stop = nullptr);

 private:
  rt::Scenario scenario_;
  rt::Emulator emulator_;
  rt::BuiltinController controller_;
  std::vector<Observer*> observers_;
};

}  // namespace csp::run
