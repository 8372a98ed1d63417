#include "csp/rt/robot_state.hpp"

#include <string>

namespace csp::rt {

const char* robot_mode_name(RobotMode mode) {
  switch (mode) {
    case RobotMode::kOther: return "Other";
    case RobotMode::kIdle: return "Idle";
    case RobotMode::kMove: return "Move";
    case RobotMode::kGuiding: return "Guiding";
    case RobotMode::kReflex: return "Reflex";
    case RobotMode::kUserStopped: return "UserStopped";
    case RobotMode::kAutomaticErrorRecovery: return "AutomaticErrorRecovery";
  }
  return "Other";
}

namespace {

// The JSON value of each field type of RobotState.
template <std::size_t N>
void json_value(std::ostream& out, const std::array<double, N>& values) {
  out << '[';
  for (std::size_t i = 0; i < N; ++i) out << (i ? "," : "") << values[i];
  out << ']';
}
void json_value(std::ostream& out, double value) { out << value; }
void json_value(std::ostream& out, const franka::Errors& errors) { out << errors; }
void json_value(std::ostream& out, RobotMode mode) { out << '"' << robot_mode_name(mode) << '"'; }
void json_value(std::ostream& out, Duration time) { out << time.toMSec(); }

}  // namespace

}  // namespace csp::rt

namespace franka {

std::ostream& operator<<(std::ostream& ostream, RobotMode robot_mode) {
  return ostream << csp::rt::robot_mode_name(robot_mode);
}

std::ostream& operator<<(std::ostream& out, const RobotState& s) {
  using csp::rt::json_value;
  const char* separator = "";
  out << '{';
#define CSP_FIELD(name)                 \
  out << separator << "\"" #name "\":"; \
  json_value(out, s.name);              \
  separator = ",";
  CSP_ROBOT_STATE_FIELDS(CSP_FIELD, CSP_FIELD)
#undef CSP_FIELD
  return out << '}';
}

}  // namespace franka
