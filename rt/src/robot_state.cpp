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

template <std::size_t N>
void field(std::ostream& out, const char* name, const std::array<double, N>& values) {
  out << '"' << name << "\":[";
  for (std::size_t i = 0; i < N; ++i) out << (i ? "," : "") << values[i];
  out << "],";
}

void field(std::ostream& out, const char* name, double value) { out << '"' << name << "\":" << value << ','; }

}  // namespace

std::ostream& operator<<(std::ostream& out, const RobotState& s) {
  out << '{';
#define CSP_FIELD(name) field(out, #name, s.name);
  CSP_FIELD(O_T_EE) CSP_FIELD(O_T_EE_d) CSP_FIELD(F_T_EE) CSP_FIELD(F_T_NE) CSP_FIELD(NE_T_EE) CSP_FIELD(EE_T_K)
  CSP_FIELD(m_ee) CSP_FIELD(I_ee) CSP_FIELD(F_x_Cee) CSP_FIELD(m_load) CSP_FIELD(I_load) CSP_FIELD(F_x_Cload)
  CSP_FIELD(m_total) CSP_FIELD(I_total) CSP_FIELD(F_x_Ctotal) CSP_FIELD(elbow) CSP_FIELD(elbow_d)
  CSP_FIELD(elbow_c) CSP_FIELD(delbow_c) CSP_FIELD(ddelbow_c) CSP_FIELD(tau_J) CSP_FIELD(tau_J_d)
  CSP_FIELD(dtau_J) CSP_FIELD(q) CSP_FIELD(q_d) CSP_FIELD(dq) CSP_FIELD(dq_d) CSP_FIELD(ddq_d)
  CSP_FIELD(joint_contact) CSP_FIELD(cartesian_contact) CSP_FIELD(joint_collision)
  CSP_FIELD(cartesian_collision) CSP_FIELD(tau_ext_hat_filtered) CSP_FIELD(O_F_ext_hat_K)
  CSP_FIELD(K_F_ext_hat_K) CSP_FIELD(O_dP_EE_d) CSP_FIELD(O_ddP_O) CSP_FIELD(O_T_EE_c) CSP_FIELD(O_dP_EE_c)
  CSP_FIELD(O_ddP_EE_c) CSP_FIELD(theta) CSP_FIELD(dtheta)
#undef CSP_FIELD
  out << "\"current_errors\":" << s.current_errors << ",\"last_motion_errors\":" << s.last_motion_errors
      << ",\"control_command_success_rate\":" << s.control_command_success_rate << ",\"robot_mode\":\""
      << robot_mode_name(s.robot_mode) << "\",\"time\":" << s.time.toMSec() << '}';
  return out;
}

}  // namespace csp::rt
