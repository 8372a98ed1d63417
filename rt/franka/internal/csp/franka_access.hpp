// CSP's own access to the emulated robot behind franka::Robot, for CSP's tests and tools only
// (not installed: a libfranka program sees the franka headers alone).
//   csp::franka_access::EmulatedRobot robot(scenario);   // a franka::Robot from a Scenario in code
//   robot.emulator().counters();  robot.lastTiming();  robot.setCycleObserver(csv_log);
#pragma once

#include <memory>

#include "../../src/robot_impl.hpp"
#include "csp/rt/scenario.hpp"
#include "franka/robot.h"

namespace csp::franka_access {

class EmulatedRobot : public franka::Robot {
 public:
  explicit EmulatedRobot(const csp::rt::Scenario& scenario,
                         franka::RealtimeConfig realtime_config = franka::RealtimeConfig::kEnforce,
                         std::size_t log_size = 50)
      : EmulatedRobot(std::make_shared<franka::Robot::Impl>(scenario, realtime_config, log_size)) {}

  // The emulated robot itself, e.g. to read its counters or settings.
  csp::rt::Emulator& emulator() { return impl_->emulator; }
  // Timing of the last motion: cycles, lost commands, overruns, controller compute time.
  const csp::rt::TimingReport& lastTiming() const { return impl_->last_timing; }
  // Called after every cycle of a motion with the published state, e.g. a csp::rt::CsvLog.
  void setCycleObserver(csp::rt::CycleObserver observer) { impl_->user_observer = std::move(observer); }
  // Whether robot time runs between the program's calls (default); off for bit-reproducible tests.
  void setIdleTimeRuns(bool runs) { impl_->idle_time_runs = runs; }

 private:
  explicit EmulatedRobot(std::shared_ptr<franka::Robot::Impl> impl) : franka::Robot(impl), impl_(std::move(impl)) {}
  std::shared_ptr<franka::Robot::Impl> impl_;
};

// The emulated robot with robot time moving only inside calls: bit-reproducible runs.
struct LockstepRobot : EmulatedRobot {
  explicit LockstepRobot(const csp::rt::Scenario& scenario) : EmulatedRobot(scenario) { setIdleTimeRuns(false); }
};

}  // namespace csp::franka_access
