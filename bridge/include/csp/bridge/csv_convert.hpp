// LCM logs as joint logs (docs/joint-log.md): an LCM log is a second container of the joint-log
// rows. `csp log export` writes its robot states as a CSV joint log (rt::CsvLog), `csp log import`
// turns a CSV joint log into an LCM log, and `csp gap --log session.lcmlog` reads the states
// directly. All three see the same states: for_each_logged_state.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "csp/dynamics/progress.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/rt/robot_state.hpp"

namespace csp::bridge {

struct ExportReport {
  uint64_t rows = 0;
  uint64_t repeated = 0;    // states published again while the robot waited (same message_id): skipped
  uint64_t rejected = 0;    // events on the state channel that are not a robot_state_t (read_state_event)
  std::string refused;      // the first of them, as read_state_event names it; empty if none
  std::string damage;       // LogReader::damage_summary(): empty for an intact log
  std::string missing;      // StateCoverage::missing(): the states a recording misses; empty if none
};

// Calls `visit(state, command_received)` for every robot state on `state_channel` of an LCM log,
// in order, once each: a state published again unchanged (same message_id; utime aside) is
// skipped, an event that is no robot state (read_state_event, the rule csp replay applies too)
// counted as rejected and the first named. `progress`: MB of the log read.
ExportReport for_each_logged_state(const std::string& log_path, const std::string& state_channel,
                                   const std::function<void(const rt::RobotState&, bool command_received)>& visit,
                                   const Progress& progress = {});

// True if `path` is a regular file that starts with an LCM log event's magic number (0xEDA1DA01),
// whatever its name.
bool is_lcm_log(const std::string& path);

// Writes every state on `state_channel` (default CSP_STATE) as one CSV row (rt::CsvLog). The
// report says what it could not export (damage, refused events): `csp log export` names it and
// exits 1.
ExportReport export_csv(const std::string& log_path, const std::string& csv_path, const std::string& state_channel,
                        const Progress& progress = {});

// The states on `state_channel` as a joint log, checked as a CSV joint log is (check_joint_log);
// throws JointLogError naming the file when the channel holds fewer than 2 states, the log is
// damaged or an event on the channel is no robot state (a diagnosis must not run on a log with
// holes it does not know of).
JointLog read_joint_log_lcm(const std::string& log_path, const std::string& state_channel, const Progress& progress = {});

// Reads a CSV joint log (read_joint_log_csv) and writes one robot_state_t per row on
// `state_channel`, with the optional groups the log has (rt::state_from_row): time is t in whole
// milliseconds (libfranka's resolution), utime t in microseconds, message_id the row number.
// Returns the rows; throws JointLogError naming the file, line and column of bad input.
uint64_t import_csv(const std::string& csv_path, const std::string& log_path, const std::string& state_channel);

}  // namespace csp::bridge
