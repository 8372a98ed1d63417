#include "csp/rt/csv_log.hpp"

#include <cmath>
#include <tuple>
#include <type_traits>
#include <utility>

namespace csp::rt {
namespace {

// Error names joined by '|' (not ", " as libfranka prints them) keep the column one word.
std::string errors_text(const ErrorSet& errors) {
  std::string text = "[";
  for (int i = 0; i < kNumErrors; ++i) {
    if (!errors.flags()[i]) continue;
    if (text.size() > 1) text += '|';
    text += error_name(static_cast<Error>(i));
  }
  return text + "]";
}

ErrorSet errors_from_text(const std::string& text, const std::string& where) {
  if (text.size() < 2 || text.front() != '[' || text.back() != ']')
    throw JointLogError(where + "current_errors: expected [name1|name2] or [], got " + quote_input(text));
  ErrorSet errors;
  const std::string names = text.substr(1, text.size() - 2);
  for (std::size_t begin = 0; begin < names.size();) {
    const std::size_t end = std::min(names.find('|', begin), names.size());
    const std::string name = names.substr(begin, end - begin);
    int found = -1;
    for (int i = 0; i < kNumErrors; ++i)
      if (name == error_name(static_cast<Error>(i))) found = i;
    if (found < 0) throw JointLogError(where + "current_errors: unknown error name " + quote_input(name) + " (libfranka's franka::Errors)");
    errors.set(static_cast<Error>(found));
    begin = end + 1;
  }
  return errors;
}

RobotMode robot_mode_from_name(const std::string& name, const std::string& where) {
  for (const RobotMode mode : {RobotMode::kOther, RobotMode::kIdle, RobotMode::kMove, RobotMode::kGuiding, RobotMode::kReflex,
                               RobotMode::kUserStopped, RobotMode::kAutomaticErrorRecovery})
    if (name == robot_mode_name(mode)) return mode;
  throw JointLogError(where + "robot_mode: unknown mode " + quote_input(name) + " (libfranka's franka::RobotMode)");
}

// The groups that are a RobotState array as it is: one list for both directions of the mapping.
template <class Visit>
void for_each_array_group(Visit&& each) {
  const auto visit = [&](auto field, auto group) {
    using Array = std::decay_t<decltype(std::declval<RobotState>().*field)>;
    using Vector = typename std::decay_t<decltype(std::declval<JointLog>().*group)>::value_type;
    static_assert(std::tuple_size_v<Array> == Vector::RowsAtCompileTime, "a group's width differs from its field's");
    each(field, group);
  };
  visit(&RobotState::q, &JointLog::q);
  visit(&RobotState::dq, &JointLog::dq);
  visit(&RobotState::tau_J, &JointLog::tau_J);
  visit(&RobotState::tau_J_d, &JointLog::tau_J_d);
  visit(&RobotState::q_d, &JointLog::q_d);
  visit(&RobotState::dq_d, &JointLog::dq_d);
  visit(&RobotState::ddq_d, &JointLog::ddq_d);
  visit(&RobotState::dtau_J, &JointLog::dtau_J);
  visit(&RobotState::tau_ext_hat_filtered, &JointLog::tau_ext_hat_filtered);
  visit(&RobotState::O_F_ext_hat_K, &JointLog::O_F_ext_hat_K);
  visit(&RobotState::O_T_EE, &JointLog::O_T_EE);
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
  for_each_array_group([&](auto field, auto group) { (log.*group).emplace_back((s.*field).data()); });
  log.robot_mode.emplace_back(robot_mode_name(s.robot_mode));
  log.command_received.push_back(command_received ? 1.0 : 0.0);
  log.control_command_success_rate.push_back(s.control_command_success_rate);
  log.current_errors.push_back(errors_text(ErrorSet(s.current_errors)));
}

RobotState state_from_row(const JointLog& log, std::size_t row) {
  const std::string where = log.source + ": row " + std::to_string(row + 1) + ": ";
  if (log.t[row] < 0.0) throw JointLogError(where + "expected t >= 0 for a robot state");
  RobotState s;
  s.time = Duration(static_cast<uint64_t>(std::llround(log.t[row] * 1e3)));   // libfranka's 1 ms resolution
  for_each_array_group([&](auto field, auto group) {
    const auto& series = log.*group;
    using Vector = typename std::decay_t<decltype(series)>::value_type;
    if (!series.empty()) Eigen::Map<Vector>((s.*field).data()) = series[row];   // the groups the log has
  });
  s.robot_mode = log.robot_mode.empty() ? RobotMode::kMove : robot_mode_from_name(log.robot_mode[row], where);
  if (!log.control_command_success_rate.empty()) s.control_command_success_rate = log.control_command_success_rate[row];
  if (!log.current_errors.empty()) s.current_errors = errors_from_text(log.current_errors[row], where).errors();
  return s;
}

CsvLog::CsvLog(const std::string& path) : row_(state_layout()), writer_(path, row_) { row_.clear_rows(); }

void CsvLog::flush() { writer_.flush(); }

void CsvLog::write(const RobotState& state, const CycleInfo& cycle) {
  row_.clear_rows();
  append_state(row_, state, cycle.command_received);
  writer_.write_row(row_, 0);
  ++rows_;
}

}  // namespace csp::rt
