#include "csp/bridge/messages.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "csp/dynamics/arrays.hpp"

namespace csp::bridge {
namespace {

// A RobotState field and its message field (the same name, csp/rt/robot_state.hpp's list):
// an std::array and a C array of the same length, or two doubles.
template <std::size_t N>
void copy(const std::array<double, N>& from, double (&to)[N]) {
  std::copy(from.begin(), from.end(), to);
}
template <std::size_t N>
void copy(const double (&from)[N], std::array<double, N>& to) {
  std::copy(from, from + N, to.begin());
}
void copy(double from, double& to) { to = from; }

// The numbers of a message field: a C array or one double.
template <std::size_t N>
const double* values_of(const double (&field)[N]) {
  return field;
}
const double* values_of(const double& field) { return &field; }
template <std::size_t N>
std::size_t count_of(const double (&)[N]) {
  return N;
}
std::size_t count_of(double) { return 1; }

// The RobotState fields of other types than double: each function below converts them by hand.
#define CSP_BY_HAND(name)

void errors_to_message(const franka::Errors& errors, int8_t (&out)[rt::kNumErrors]) {
  const rt::ErrorSet set(errors);
  for (int i = 0; i < rt::kNumErrors; ++i) out[i] = set.flags()[i] ? 1 : 0;
}

franka::Errors errors_from_message(const int8_t (&in)[rt::kNumErrors]) {
  std::array<bool, rt::kNumErrors> errors{};
  for (int i = 0; i < rt::kNumErrors; ++i) errors[i] = in[i] != 0;
  return franka::Errors(errors);
}

int64_t big_endian_int64(const void* data) {
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  return static_cast<int64_t>(v);
}

template <typename T>
bool has_fingerprint(const void* data, int size) {
  return size >= 8 && big_endian_int64(data) == T::getHash();
}

template <typename T>
Rejection decode_command_as(const void* data, int size, rt::ControlMode mode, ReceivedCommand& out) {
  T message;
  const Rejection rejection = decode_exact(data, size, message);
  if (rejection != Rejection::kNone) return rejection;
  out.mode = mode;
  out.message_id = message.message_id;
  if constexpr (std::is_same_v<T, torque_command_t>) out.command.values = from_array<Vector7>(message.tau_J);
  if constexpr (std::is_same_v<T, joint_position_command_t>) out.command.values = from_array<Vector7>(message.q);
  if constexpr (std::is_same_v<T, joint_velocity_command_t>) out.command.values = from_array<Vector7>(message.dq);
  out.command.motion_finished = message.motion_finished != 0;
  return Rejection::kNone;
}

template <typename T>
std::vector<uint8_t> encode_command_as(int64_t message_id, const rt::Command& command, int64_t utime, double (&values)[7], T& message) {
  message.utime = utime;
  message.message_id = message_id;
  std::copy(command.values.data(), command.values.data() + kNumJoints, values);
  message.motion_finished = command.motion_finished ? 1 : 0;
  return encode(message);
}

// A 4x4 column-major pose; throws if it is not a finite rigid transform.
Transform transform_from(const double (&values)[16], const char* operation) {
  const std::optional<Transform> pose = rigid_transform_from_matrix(from_array<Eigen::Matrix4d>(values));
  if (!pose) throw std::invalid_argument(std::string(operation) + ": expected a rigid transform (4x4 column-major, finite)");
  return *pose;
}

}  // namespace

Channels::Channels(const std::string& p)
    : prefix(p),
      state(p + "CSP_STATE"),
      command(p + "CSP_COMMAND"),
      config(p + "CSP_CONFIG"),
      config_reply(p + "CSP_CONFIG_REPLY"),
      status(p + "CSP_STATUS"),
      scenario(p + "CSP_SCENARIO"),
      event(p + "CSP_EVENT") {}

int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

robot_state_t to_message(const rt::RobotState& s, int64_t utime, bool command_received) {
  robot_state_t m{};
  m.utime = utime;
  m.message_id = static_cast<int64_t>(s.time.toMSec());
  m.command_received = command_received ? 1 : 0;
#define CSP_TO(name) copy(s.name, m.name);
  CSP_ROBOT_STATE_FIELDS(CSP_TO, CSP_BY_HAND)
#undef CSP_TO
  errors_to_message(s.current_errors, m.current_errors);
  errors_to_message(s.last_motion_errors, m.last_motion_errors);
  m.robot_mode = static_cast<int8_t>(s.robot_mode);
  m.time = static_cast<int64_t>(s.time.toMSec());
  return m;
}

rt::RobotState from_message(const robot_state_t& m) {
  rt::RobotState s;
#define CSP_FROM(name) copy(m.name, s.name);
  CSP_ROBOT_STATE_FIELDS(CSP_FROM, CSP_BY_HAND)
#undef CSP_FROM
  s.current_errors = errors_from_message(m.current_errors);
  s.last_motion_errors = errors_from_message(m.last_motion_errors);
  const bool known_mode = m.robot_mode >= robot_state_t::MODE_OTHER && m.robot_mode <= robot_state_t::MODE_AUTOMATIC_ERROR_RECOVERY;
  s.robot_mode = known_mode ? static_cast<rt::RobotMode>(m.robot_mode) : rt::RobotMode::kOther;
  s.time = rt::Duration(static_cast<uint64_t>(std::max<int64_t>(m.time, 0)));
  return s;
}

double state_difference(const robot_state_t& a, const robot_state_t& b, std::string& field) {
  field.clear();
  double difference = 0.0;
  const auto compare = [&](const char* name, const double* x, const double* y, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      // Bit for bit: NaN equals NaN, -0 differs from +0.
      if (std::memcmp(&x[i], &y[i], sizeof(double)) == 0) continue;
      if (field.empty()) field = name;
      const double d = std::abs(x[i] - y[i]);
      difference = std::max(difference, std::isnan(d) || d == 0.0 ? std::numeric_limits<double>::min() : d);
    }
  };
#define CSP_COMPARE(name) compare(#name, values_of(a.name), values_of(b.name), count_of(a.name));
  CSP_ROBOT_STATE_FIELDS(CSP_COMPARE, CSP_BY_HAND)
#undef CSP_COMPARE
  const auto flag = [&](const char* name, bool same) {
    if (same) return;
    if (field.empty()) field = name;
    difference = std::numeric_limits<double>::infinity();
  };
  flag("current_errors", std::equal(std::begin(a.current_errors), std::end(a.current_errors), std::begin(b.current_errors)));
  flag("last_motion_errors", std::equal(std::begin(a.last_motion_errors), std::end(a.last_motion_errors), std::begin(b.last_motion_errors)));
  flag("robot_mode", a.robot_mode == b.robot_mode);
  flag("message_id", a.message_id == b.message_id && a.time == b.time);
  flag("command_received", a.command_received == b.command_received);
  return difference;
}

const char* rejection_name(Rejection rejection) {
  switch (rejection) {
    case Rejection::kNone: return "accepted";
    case Rejection::kFingerprint: return "unknown type (fingerprint mismatch)";
    case Rejection::kTruncated: return "truncated";
    case Rejection::kOversized: return "oversized";
  }
  return "unknown";
}

template <typename T>
Rejection decode_exact(const void* data, int size, T& out) {
  if (size >= 8 && !has_fingerprint<T>(data, size)) return Rejection::kFingerprint;
  if (size < 8) return Rejection::kTruncated;
  // lcm-gen's string decoder trusts the encoded length: a length of 0 or below makes it ask
  // std::string for ~2^64 characters (std::length_error). Such a message is malformed.
  try {
    if (out.decode(data, 0, size) < 0) return Rejection::kTruncated;
  } catch (const std::length_error&) {
    return Rejection::kTruncated;
  }
  if (size != out.getEncodedSize()) return Rejection::kOversized;
  return Rejection::kNone;
}

template Rejection decode_exact(const void*, int, robot_state_t&);
template Rejection decode_exact(const void*, int, config_request_t&);
template Rejection decode_exact(const void*, int, config_reply_t&);
template Rejection decode_exact(const void*, int, status_t&);
template Rejection decode_exact(const void*, int, scenario_t&);
template Rejection decode_exact(const void*, int, event_t&);

Rejection decode_command(const void* data, int size, ReceivedCommand& out) {
  if (has_fingerprint<torque_command_t>(data, size))
    return decode_command_as<torque_command_t>(data, size, rt::ControlMode::kTorque, out);
  if (has_fingerprint<joint_position_command_t>(data, size))
    return decode_command_as<joint_position_command_t>(data, size, rt::ControlMode::kJointPosition, out);
  if (has_fingerprint<joint_velocity_command_t>(data, size))
    return decode_command_as<joint_velocity_command_t>(data, size, rt::ControlMode::kJointVelocity, out);
  return size < 8 ? Rejection::kTruncated : Rejection::kFingerprint;
}

std::vector<uint8_t> encode_command(rt::ControlMode mode, int64_t message_id, const rt::Command& command, int64_t utime) {
  switch (mode) {
    case rt::ControlMode::kTorque: {
      torque_command_t m{};
      return encode_command_as(message_id, command, utime, m.tau_J, m);
    }
    case rt::ControlMode::kJointPosition: {
      joint_position_command_t m{};
      return encode_command_as(message_id, command, utime, m.q, m);
    }
    case rt::ControlMode::kJointVelocity: {
      joint_velocity_command_t m{};
      return encode_command_as(message_id, command, utime, m.dq, m);
    }
    case rt::ControlMode::kCartesianPose:
    case rt::ControlMode::kCartesianVelocity: break;
  }
  throw std::invalid_argument(std::string("the LCM bridge carries torque and joint commands, not ") +
                              rt::control_mode_name(mode));
}

int8_t control_mode_code(rt::ControlMode mode) {
  switch (mode) {
    case rt::ControlMode::kTorque: return config_request_t::CONTROL_TORQUE;
    case rt::ControlMode::kJointPosition: return config_request_t::CONTROL_JOINT_POSITION;
    case rt::ControlMode::kJointVelocity: return config_request_t::CONTROL_JOINT_VELOCITY;
    case rt::ControlMode::kCartesianPose:
    case rt::ControlMode::kCartesianVelocity: break;   // not carried by the LCM bridge
  }
  return -1;
}

std::optional<rt::ControlMode> control_mode_from_code(int8_t code) {
  switch (code) {
    case config_request_t::CONTROL_TORQUE: return rt::ControlMode::kTorque;
    case config_request_t::CONTROL_JOINT_POSITION: return rt::ControlMode::kJointPosition;
    case config_request_t::CONTROL_JOINT_VELOCITY: return rt::ControlMode::kJointVelocity;
    default: return std::nullopt;
  }
}

void apply_configuration(const config_request_t& r, rt::Emulator& emulator) {
  switch (r.request) {
    case config_request_t::SET_COLLISION_BEHAVIOR: {
      const rt::CollisionBehavior b = rt::collision_behavior(
          std::to_array(r.lower_torque_thresholds_acceleration), std::to_array(r.upper_torque_thresholds_acceleration),
          std::to_array(r.lower_torque_thresholds_nominal), std::to_array(r.upper_torque_thresholds_nominal),
          std::to_array(r.lower_force_thresholds_acceleration), std::to_array(r.upper_force_thresholds_acceleration),
          std::to_array(r.lower_force_thresholds_nominal), std::to_array(r.upper_force_thresholds_nominal));
      for (const auto* v : {&b.lower_torque_acceleration, &b.upper_torque_acceleration, &b.lower_torque_nominal, &b.upper_torque_nominal})
        if (!v->allFinite() || (v->array() < 0.0).any())
          throw std::invalid_argument("setCollisionBehavior: expected finite non-negative torque thresholds");
      for (const auto* v : {&b.lower_force_acceleration, &b.upper_force_acceleration, &b.lower_force_nominal, &b.upper_force_nominal})
        if (!v->allFinite() || (v->array() < 0.0).any())
          throw std::invalid_argument("setCollisionBehavior: expected finite non-negative force thresholds");
      emulator.set_collision_behavior(b);
      return;
    }
    case config_request_t::SET_JOINT_IMPEDANCE: emulator.set_joint_impedance(from_array<Vector7>(r.K_theta)); return;
    case config_request_t::SET_LOAD: {
      RigidBodyInertia load;
      load.mass = r.load_mass;
      load.com = from_array<Vector3>(r.F_x_Cload);
      load.inertia = from_array<Matrix3>(r.load_inertia);   // column-major like I_load
      emulator.set_load(load);
      return;
    }
    case config_request_t::SET_EE: emulator.set_EE(transform_from(r.NE_T_EE, "setEE")); return;
    case config_request_t::SET_K: emulator.set_K(transform_from(r.EE_T_K, "setK")); return;
    case config_request_t::AUTOMATIC_ERROR_RECOVERY: emulator.automatic_error_recovery(); return;
    default:
      throw std::invalid_argument("unknown request " + std::to_string(r.request) + " (expected 1 to 7, see config_request_t)");
  }
}

}  // namespace csp::bridge
