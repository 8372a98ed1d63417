// The LCM messages of the bridge (lcm/*.lcm, docs/bridge.md): channel names, conversions between
// the emulator's types and the generated ones, and strict decoding of what arrives from the
// network (a message is accepted only if it is exactly one message of an expected type).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "csp/config_reply_t.hpp"
#include "csp/config_request_t.hpp"
#include "csp/event_t.hpp"
#include "csp/joint_position_command_t.hpp"
#include "csp/joint_velocity_command_t.hpp"
#include "csp/robot_state_t.hpp"
#include "csp/scenario_t.hpp"
#include "csp/status_t.hpp"
#include "csp/torque_command_t.hpp"
#include "csp/rt/control_loop.hpp"

namespace csp::bridge {

// UDP multicast on loopback, ttl=0: nothing leaves the machine.
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

// The channel names, each with the prefix so that several robots can share a bus.
struct Channels {
  explicit Channels(const std::string& prefix = "");
  std::string prefix, state, command, config, config_reply, status, scenario, event;
};

// Microseconds since the Unix epoch (LCM's utime).
int64_t now_utime();

robot_state_t to_message(const rt::RobotState& state, int64_t utime, bool command_received);
rt::RobotState from_message(const robot_state_t& message);

// Largest |a - b| over the numeric fields (utime aside); infinity if errors, mode or id differ.
// The name of the first field that differs goes to `field` (empty when identical).
double state_difference(const robot_state_t& a, const robot_state_t& b, std::string& field);

// Why an inbound message was refused.
enum class Rejection { kNone, kFingerprint, kTruncated, kOversized };
const char* rejection_name(Rejection rejection);

// Decodes `out` if `data` is exactly one encoded T (its fingerprint, its whole length).
template <typename T>
Rejection decode_exact(const void* data, int size, T& out);

// A command of any of the three modes as it arrives on the command channel.
struct ReceivedCommand {
  rt::ControlMode mode = rt::ControlMode::kTorque;
  int64_t message_id = -1;
  rt::Command command;
};
// kNone and the command, or why the bytes are not one command message.
Rejection decode_command(const void* data, int size, ReceivedCommand& out);
std::vector<uint8_t> encode_command(rt::ControlMode mode, int64_t message_id, const rt::Command& command, int64_t utime);

// The control modes as config_request_t::control_mode codes.
int8_t control_mode_code(rt::ControlMode mode);
std::optional<rt::ControlMode> control_mode_from_code(int8_t code);

// Applies a configuration request (not START_MOTION) to the emulator; throws
// std::invalid_argument or rt::InvalidOperation naming what was wrong.
void apply_configuration(const config_request_t& request, rt::Emulator& emulator);

// Encodes any generated message into bytes.
template <typename T>
std::vector<uint8_t> encode(const T& message) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace csp::bridge
