// The per-cycle CSV log of `csp emulate`, in the joint-log format (csp/io/joint_log.hpp,
// docs/joint-log.md): t, q, dq, tau_J first as in the real Panda log, then the other groups the
// robot state reports. The same run gives the same bytes. Each row reaches the file when it is
// written (JointLogCsvWriter), also when a controller failure unwinds.
#pragma once

#include <string>

#include "csp/io/joint_log.hpp"
#include "csp/rt/control_loop.hpp"

namespace csp::rt {

// The robot state as one joint-log row, and back: the one mapping between RobotState and the
// joint-log groups (the CSV log, LCM export and import, csp gap on LCM logs use it).
void append_state(JointLog& log, const RobotState& state, bool command_received);
// Row `row` of `log` as a robot state: the groups the log has, the rest default. Without
// robot_mode the robot is in Move. Throws JointLogError for an unknown mode or error name.
RobotState state_from_row(const JointLog& log, std::size_t row);

class CsvLog {
 public:
  explicit CsvLog(const std::string& path);   // throws JointLogError if it cannot be written
  CsvLog(const CsvLog&) = delete;
  CsvLog& operator=(const CsvLog&) = delete;

  // Throw JointLogError naming the file when a write fails (JointLogCsvWriter: the file then ends
  // at its last complete row); flush() again says so, at the end of a run.
  void write(const RobotState& state, const CycleInfo& cycle);
  void flush();
  uint64_t rows() const { return rows_; }
  const std::string& path() const { return writer_.path(); }

 private:
  JointLog row_;   // the row being written (memory reused cycle after cycle)
  JointLogCsvWriter writer_;
  uint64_t rows_ = 0;
};

}  // namespace csp::rt
