#include "csp/rt/csv_log.hpp"

#include <cmath>

namespace csp::rt {
namespace {

// Error names joined by '|' (not ", " as libfranka prints them) keep the column one word.
std::string errors_text(const Errors& errors) {
  std::string text = "[";
  for (int i = 0; i < kNumErrors; ++i) {
    if (!errors.errors()[i]) continue;
    if (text.size() > 1) text += '|';
    text += error_name(static_cast<Error>(i));
  }
  return text + "]";
}

Errors errors_from_text(const std::string& text, const std::string& where) {
  if (text.size() < 2 || text.front() != '[' || text.back() != ']')
    throw JointLogError(where + "current_errors: expected [name1|name2] or [], got `" + text + "`");
  Errors errors;
  const std::string names = text.substr(1, text.size() - 2);
  for (std::size_t begin = 0; begin < names.size();) {
    const std::size_t end = std::min(names.find('|', begin), names.size());
    const std::string name = names.substr(begin, end - begin);
    int found = -1;
    for (int i = 0; i < kNumErrors; ++i)
      if (name == error_name(static_cast<Error>(i))) found = i;
    if (found < 0) throw JointLogError(where + "current_errors: unknown error name `" + name + "` (libfranka's franka::Errors)");
    errors.set(static_cast<Error>(found));
    begin = end + 1;
  }
  return errors;
}

RobotMode robot_mode_from_name(const std::string& name, const std::string& where) {
  for (const RobotMode mode : {RobotMode::kOther, RobotMode::kIdle, RobotMode::kMove, RobotMode::kGuiding, RobotMode::kReflex,
                               RobotMode::kUserStopped, RobotMode::kAutomaticErrorRecovery})
    if (name == robot_mode_name(mode)) return mode;
  throw JointLogError(where + "robot_mode: unknown mode `" + name + "` (libfranka's franka::RobotMode)");
}

// A group's row into a state field, when the log has the group.
template <class Vector, std::size_t N>
void copy_row(const std::vector<Vector>& series, std::size_t row, std::array<double, N>& field) {
  static_assert(Vector::RowsAtCompileTime == N);
  if (!series.empty()) Eigen::Map<Vector>(field.data()) = series[row];
}

// The state the emulator's log starts from, only to know which groups a state fills.
JointLog state_layout() {
  JointLog layout;
  append_state(layout, RobotState{}, false);
  return layout;
}

}  // namespace

void append_state(JointLog& log, const RobotState& s, bool command_received) {
  log.t.push_back(s.time.toSec());
  log.q.emplace_back(s.q.data());
  log.dq.emplace_back(s.dq.data());
  log.tau_J.emplace_back(s.tau_J.data());
  log.tau_J_d.emplace_back(s.tau_J_d.data());
  log.q_d.emplace_back(s.q_d.data());
  log.dq_d.emplace_back(s.dq_d.data());
  log.ddq_d.emplace_back(s.ddq_d.data());
  log.dtau_J.emplace_back(s.dtau_J.data());
  log.tau_ext_hat_filtered.emplace_back(s.tau_ext_hat_filtered.data());
  log.O_F_ext_hat_K.emplace_back(s.O_F_ext_hat_K.data());
  log.O_T_EE.emplace_back(s.O_T_EE.data());
  log.robot_mode.emplace_back(robot_mode_name(s.robot_mode));
  log.command_received.push_back(command_received ? 1.0 : 0.0);
  log.control_command_success_rate.push_back(s.control_command_success_rate);
  log.current_errors.push_back(errors_text(s.current_errors));
}

RobotState state_from_row(const JointLog& log, std::size_t row) {
  const std::string where = log.source + ": row " + std::to_string(row + 1) + ": ";
  if (log.t[row] < 0.0) throw JointLogError(where + "expected t >= 0 for a robot state");
  RobotState s;
  s.time = Duration(static_cast<uint64_t>(std::llround(log.t[row] * 1e3)));   // libfranka's 1 ms resolution
  copy_row(log.q, row, s.q);
  copy_row(log.dq, row, s.dq);
  copy_row(log.tau_J, row, s.tau_J);
  copy_row(log.tau_J_d, row, s.tau_J_d);
  copy_row(log.q_d, row, s.q_d);
  copy_row(log.dq_d, row, s.dq_d);
  copy_row(log.ddq_d, row, s.ddq_d);
  copy_row(log.dtau_J, row, s.dtau_J);
  copy_row(log.tau_ext_hat_filtered, row, s.tau_ext_hat_filtered);
  copy_row(log.O_F_ext_hat_K, row, s.O_F_ext_hat_K);
  copy_row(log.O_T_EE, row, s.O_T_EE);
  s.robot_mode = log.robot_mode.empty() ? RobotMode::kMove : robot_mode_from_name(log.robot_mode[row], where);
  if (!log.control_command_success_rate.empty()) s.control_command_success_rate = log.control_command_success_rate[row];
  if (!log.current_errors.empty()) s.current_errors = errors_from_text(log.current_errors[row], where);
  return s;
}

CsvLog::CsvLog(const std::string& path) : row_(state_layout()), writer_(path, row_) { row_.clear_rows(); }

CsvLog::~CsvLog() { writer_.flush(); }

void CsvLog::write(const RobotState& state, const CycleInfo& cycle) {
  row_.clear_rows();
  append_state(row_, state, cycle.command_received);
  writer_.write_row(row_, 0);
  ++rows_;
}

}  // namespace csp::rt
