#include "csp/rt/robot_state.hpp"

#include <string>

namespace csp::rt {

const char* error_name(Error error) {
  switch (error) {
#define CSP_NAME_CASE(name) \
  case Error::name: return #name;
    CSP_FRANKA_ERRORS(CSP_NAME_CASE)
#undef CSP_NAME_CASE
  }
  return "unknown_error";
}

Errors::operator bool() const noexcept {
  for (bool e : errors_)
    if (e) return true;
  return false;
}

Errors::operator std::string() const {
  std::string out = "[";
  for (int i = 0; i < kNumErrors; ++i) {
    if (!errors_[i]) continue;
    if (out.size() > 1) out += ", ";
    out += error_name(static_cast<Error>(i));
  }
  return out + "]";
}

std::ostream& operator<<(std::ostream& out, const Errors& errors) {
  out << '[';
  bool first = true;
  for (int i = 0; i < kNumErrors; ++i) {
    if (!errors.errors()[i]) continue;
    out << (first ? "" : ",") << '"' << error_name(static_cast<Error>(i)) << '"';
    first = false;
  }
  return out << ']';
}

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
void json_value(std::ostream& out, const Errors& errors) { out << errors; }
void json_value(std::ostream& out, RobotMode mode) { out << '"' << robot_mode_name(mode) << '"'; }
void json_value(std::ostream& out, Duration time) { out << time.toMSec(); }

}  // namespace

std::ostream& operator<<(std::ostream& out, const RobotState& s) {
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

}  // namespace csp::rt
