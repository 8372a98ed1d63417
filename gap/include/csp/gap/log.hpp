// Joint logs of a real robot (or of anything that plays one): time, joint positions, velocities and
// link-side torques, as in ../shared/data/real/*.csv. Reading validates every field and throws
// LogError naming the file, line, column and what was expected.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "csp/dynamics/spatial.hpp"

namespace csp::gap {

class LogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct JointLog {
  std::string source;          // file name (or generator description), for messages
  std::vector<double> t;       // [s], strictly increasing, not necessarily uniform
  std::vector<Vector7> q, dq;  // [rad], [rad/s]
  std::vector<Vector7> tau;    // measured link-side torque tau_J [N m], gravity included
  std::vector<Vector7> ddq;    // [rad/s^2]; empty unless the log has ddq1..ddq7
  std::size_t size() const { return t.size(); }
};

// CSV with a header row: t, q1..q7, dq1..dq7, tau_J1..tau_J7 in any order; optional ddq1..ddq7 and
// tau_J_d1..tau_J_d7 (the commanded torque, read and ignored). Every value finite, t increasing.
JointLog read_log_csv(const std::string& path);
void write_log_csv(const std::string& path, const JointLog& log);

// The rows with t in [t_begin, t_end).
JointLog slice(const JointLog& log, double t_begin, double t_end);

}  // namespace csp::gap
