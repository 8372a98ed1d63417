#include "csp/run/run.hpp"

#include <exception>

namespace csp::run {

Run::Run(const rt::Scenario& scenario)
    : scenario_(scenario),
      emulator_(scenario_.emulator),
      controller_(rt::make_controller(scenario_.controller, scenario_.controller_faults, emulator_)) {}

RunResult Run::run_builtin_controller(const std::atomic<bool>* stop) {
  RunResult result;
  // Set by the stop flag or a failed observer: the next command closes the motion.
  std::atomic<bool> halt = false;
  std::vector<Observer*> active = observers_;
  rt::LoopOptions options;
  options.clock = scenario_.clock;
  options.faults = scenario_.command_faults;
  options.max_duration = scenario_.duration;
  options.stop = &halt;
  options.observer = [&](const rt::RobotState& state, const rt::CycleInfo& cycle) {
    for (Observer*& observer : active) {
      if (!observer) continue;
      try {
        observer->on_cycle(state, cycle);
      } catch (const std::exception& e) {
        if (result.observer_failure.empty()) result.observer_failure = e.what();
        observer = nullptr;   // not called again: a log that failed stays as it was left
        halt = true;
      }
    }
    if (stop && stop->load()) halt = true;
  };
  try {
    result.motion = rt::run_motion(emulator_, controller_.mode, controller_.controller, options);
  } catch (const std::exception& e) {   // the controller threw: the robot is in Reflex, the logs are whole
    result.controller_failure = e.what();
  }
  result.stopped = stop && stop->load();
  return result;
}

}  // namespace csp::run
