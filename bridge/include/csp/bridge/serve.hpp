// `csp serve`: the emulated robot on an LCM bus (docs/bridge.md). The state is published every
// cycle whether or not a controller listens; a controller starts a control session with a
// START_MOTION request and answers each state with a command echoing its message_id.
#pragma once

#include <atomic>
#include <string>

#include "csp/bridge/server.hpp"
#include "csp/rt/cycle_driver.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::bridge {

struct ServeOptions {
  rt::Clock clock = rt::Clock::kLockstep;
  double duration = 10.0;               // robot time to run [s]
  std::string lcm_url = kDefaultLcmUrl;
  std::string channel_prefix;
  std::string log_path;                 // LCM log of the session; empty: none
  double lockstep_timeout = 1.0;        // lockstep: how long a session's cycle waits for its command [s]
  bool wait_for_controller = false;     // lockstep: hold the first cycle until a session starts
  const std::atomic<bool>* stop = nullptr;   // set (e.g. by SIGINT) to end the run cleanly
  bool quiet = false;                   // no diagnostic lines on stderr
  rt::CycleObserver after_cycle;        // after each robot cycle, once its state is published (may be empty)
};

struct ServeReport {
  rt::TimingReport timing;              // cycles, round trip publication -> command, deadlines
  ServerCounters counters;
  rt::EmulatorCounters emulator;
  double motion_wall_seconds = 0.0;     // of the cycles inside control sessions (lockstep: the controller's pace)
  uint64_t state_messages = 0;          // published (republications while waiting not counted)
  uint64_t log_events = 0;
  std::string last_reflex;
};

// Serves `robot` (the run's emulated robot, of `scenario`) for options.duration; throws
// std::runtime_error if LCM or the log cannot be opened. run::LcmBusSource is the front end.
ServeReport serve(rt::Emulator& robot, const rt::Scenario& scenario, const ServeOptions& options);

}  // namespace csp::bridge
