#include "csp/run/sources.hpp"

#include <exception>

namespace csp::run {

ControllerSource::ControllerSource(const Run& run)
    : controller_(rt::make_controller(run.scenario().controller, run.scenario().controller_faults, run.emulator())) {}

void ControllerSource::drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
                             const std::atomic<bool>& stop) {
  rt::LoopOptions options;
  options.clock = scenario.clock;
  options.faults = scenario.command_faults;
  options.max_duration = scenario.duration;
  options.stop = &stop;
  options.observer = after_cycle;
  try {
    motion_ = rt::run_motion(robot, controller_.mode, controller_.controller, options);
  } catch (const std::exception& e) {   // the controller threw: the robot is in Reflex, the logs are whole
    failure_ = e.what();
  }
}

void LcmBusSource::drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
                         const std::atomic<bool>& stop) {
  bridge::ServeOptions options = options_;
  options.stop = &stop;
  options.after_cycle = after_cycle;
  report_ = bridge::serve(robot, scenario, options);
}

// The run's scenario is the recording's: the robot was built from it.
void LogReplaySource::drive(const rt::Scenario&, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
                            const std::atomic<bool>& stop) {
  bridge::ResimulationOptions options;
  options.after_cycle = after_cycle;
  options.stop = &stop;
  options.progress = progress_;
  report_ = bridge::resimulate(recording_, robot, options);
}

}  // namespace csp::run
