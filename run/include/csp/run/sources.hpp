// The command sources of a run (run.hpp): where the robot's commands come from. Each drives the
// run's robot on rt::CycleDriver's clock and keeps its front end's report.
//
//   ControllerSource  the scenario's built-in controller in this process   csp emulate, csp plan --verify
//   LcmBusSource      controllers on the LCM bus                            csp serve
//   CanBusSource      a CANopen master on SocketCAN                         csp can serve (can_source.hpp)
//   LogReplaySource   the commands and requests a log recorded               csp replay
#pragma once

#include <string>

#include "csp/bridge/replay.hpp"
#include "csp/bridge/serve.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/run/run.hpp"

namespace csp::run {

// The scenario's built-in controller, on the scenario's clock, with its command faults, for its
// duration. The stop flag ends the motion as its duration would: the robot holds.
class ControllerSource : public CommandSource {
 public:
  // Made for `run`'s robot as it stands (its start pose) and its scenario's controller.
  explicit ControllerSource(const Run& run);

  // Its control mode and, for a medical controller, what it found (breakthrough).
  const rt::BuiltinController& controller() const { return controller_; }
  void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
             const std::atomic<bool>& stop) override;

  const rt::MotionResult& motion() const { return motion_; }   // reflex, errors, the timing report
  // The controller threw: what it said (the robot is then in Reflex, the logs are whole).
  const std::string& failure() const { return failure_; }
  bool reflex() const { return motion_.reflex || !failure_.empty(); }

 private:
  rt::BuiltinController controller_;
  rt::MotionResult motion_;
  std::string failure_;
};

// `csp serve`: the robot on the LCM bus (bridge/serve.hpp; options.stop and after_cycle are the run's).
class LcmBusSource : public CommandSource {
 public:
  explicit LcmBusSource(bridge::ServeOptions options) : options_(std::move(options)) {}
  void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
             const std::atomic<bool>& stop) override;
  const bridge::ServeReport& report() const { return report_; }

 private:
  bridge::ServeOptions options_;
  bridge::ServeReport report_;
};

// `csp replay`: a recording's commands and requests, fed cycle by cycle to the run's robot, each
// recorded state compared with the re-simulated one (bridge/replay.hpp). The run's scenario is the
// recording's (Run(recording.scenario)).
class LogReplaySource : public CommandSource {
 public:
  LogReplaySource(const bridge::Recording& recording, Progress progress) : recording_(recording), progress_(std::move(progress)) {}
  void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
             const std::atomic<bool>& stop) override;
  const bridge::ResimulationReport& report() const { return report_; }

 private:
  const bridge::Recording& recording_;
  Progress progress_;
  bridge::ResimulationReport report_;
};

}  // namespace csp::run
