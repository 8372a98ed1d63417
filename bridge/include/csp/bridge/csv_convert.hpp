// `csp log export` and `csp log import`: LCM logs <-> the CSV layout of the real Panda data
// (t, q1..q7, dq1..dq7, tau_J1..tau_J7, then rt::CsvLog's other columns), so real and emulated
// data share one format.
#pragma once

#include <string>

namespace csp::bridge {

struct ExportReport {
  uint64_t rows = 0;
  uint64_t repeated = 0;    // states published again while the robot waited (same message_id): skipped
  uint64_t rejected = 0;    // events on the state channel that are not a robot_state_t
};
// Writes every state on `state_channel` (default CSP_STATE) as one CSV row.
ExportReport export_csv(const std::string& log_path, const std::string& csv_path, const std::string& state_channel);

// Reads a real-robot CSV (columns t, q1..q7, dq1..dq7, tau_J1..tau_J7, optionally tau_J_d1..7;
// others ignored) and writes one robot_state_t per row on `state_channel`: time is t in whole
// milliseconds (libfranka's resolution), utime t in microseconds, message_id the row number. Returns the
// rows; throws std::runtime_error naming the file, line and column of bad input.
uint64_t import_csv(const std::string& csv_path, const std::string& log_path, const std::string& state_channel);

}  // namespace csp::bridge
