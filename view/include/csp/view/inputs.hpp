// What csp view shows, from what a user has: a scenario (run here, in lockstep, and shown as a
// recording), or a session log (CSV, LCM or MCAP) with the scenario it ran (the log's recorded
// one, or the one the user names), and the robot of a run shown live.
#pragma once

#include <string>

#include "csp/rt/scenario.hpp"
#include "csp/view/recording.hpp"

namespace csp::view {

// The robot and scene of a scenario as the emulator has them (the plant's parameters, with the
// scene's tool or the end effector).
ViewRobot view_robot(const rt::Scenario& scenario);

// The longest scenario `csp view SCENARIO` runs in memory (its rows are kept: about 1 kB a cycle).
inline constexpr double kMaxViewedScenarioSeconds = 600.0;

// Runs `scenario` with its built-in controller in lockstep and records every state. Throws
// std::invalid_argument for a scenario longer than kMaxViewedScenarioSeconds (record it with
// csp emulate --log and view the log).
JointLog run_scenario(const rt::Scenario& scenario);

// A session log and the robot it ran: `scenario_path` when given; else an LCM log's recorded
// scenario (if its file is still there) or its recorded robot file; else the default scenario's
// robot, without a scene. `note`: one line saying which robot was taken.
struct LogInput {
  JointLog log;
  ViewRobot robot;
  std::string note;
};
LogInput read_log_input(const std::string& log_path, const std::string& state_channel, const std::string& scenario_path);

}  // namespace csp::view
