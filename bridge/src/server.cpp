#include "csp/bridge/server.hpp"

#include <cmath>
#include <stdexcept>

namespace csp::bridge {
namespace {

// Rate limit of the diagnostic lines: the 1st, 10th, 100th, ... of each kind.
bool is_power_of_ten(uint64_t n) {
  while (n >= 10 && n % 10 == 0) n /= 10;
  return n == 1;
}

}  // namespace

RobotServer::RobotServer(rt::Emulator& robot, const Channels& channels, Send send, Diagnostic diagnostic)
    : emulator_(robot), channels_(channels), send_(std::move(send)), diagnostic_(std::move(diagnostic)) {}

robot_state_t RobotServer::state_message(int64_t utime) const {
  return to_message(emulator_.state(), utime, command_received_);
}

void RobotServer::count(uint64_t& counter, const std::string& what) {
  ++counter;
  if (is_power_of_ten(counter)) diagnostic_(what + " (" + std::to_string(counter) + " so far)");
}

bool RobotServer::accepted(Rejection rejection, const std::string& where) {
  switch (rejection) {
    case Rejection::kNone: return true;
    case Rejection::kFingerprint: count(counters_.rejected_fingerprint, where + rejection_name(rejection)); break;
    case Rejection::kTruncated: count(counters_.rejected_truncated, where + rejection_name(rejection)); break;
    case Rejection::kOversized: count(counters_.rejected_oversized, where + rejection_name(rejection)); break;
  }
  return false;
}

void RobotServer::event(const std::string& text, int64_t utime) {
  event_t e;
  e.utime = utime;
  e.time = message_id();
  e.text = text;
  send_(channels_.event, encode(e));
  diagnostic_(text);
}

void RobotServer::receive(const std::string& channel, const void* data, int size, int64_t utime) {
  if (channel == channels_.command) {
    ReceivedCommand received;
    if (accepted(decode_command(data, size, received), "message on " + channels_.command + ": ")) command(received);
  } else if (channel == channels_.config) {
    config_request_t decoded;
    if (accepted(decode_exact(data, size, decoded), "message on " + channels_.config + ": ")) request(decoded, utime);
  }
}

void RobotServer::command(const ReceivedCommand& received) {
  const std::string where = "message on " + channels_.command + ": ";
  if (!session_) return count(counters_.rejected_no_session, where + "command without a control session (send START_MOTION first)");
  if (received.mode != *session_)
    return count(counters_.rejected_wrong_mode, where + rt::control_mode_name(received.mode) +
                                                    " command in a " + rt::control_mode_name(*session_) + " session");
  if (received.message_id != message_id() || command_)
    return count(counters_.rejected_stale, where + "command answers state " + std::to_string(received.message_id) +
                                               ", the current state is " + std::to_string(message_id()));
  if (!received.command.values.allFinite())
    count(counters_.non_finite_commands, where + "non-finite command (the robot stops in a reflex)");
  command_ = received.command;
}

void RobotServer::request(const config_request_t& request, int64_t utime) {
  const std::string where = "message on " + channels_.config + ": ";
  config_reply_t reply;
  reply.request_id = request.request_id;
  reply.message_id = message_id();
  reply.ok = 1;
  try {
    if (request.request == config_request_t::START_MOTION) {
      const std::optional<rt::ControlMode> mode = control_mode_from_code(request.control_mode);
      if (!mode) throw std::invalid_argument("START_MOTION: unknown control_mode " + std::to_string(request.control_mode));
      emulator_.start_motion(*mode);
      session_ = mode;
      ++counters_.sessions;
      event(std::string("control session started (") + rt::control_mode_name(*mode) + ")", utime);
    } else {
      apply_configuration(request, emulator_);
    }
  } catch (const std::exception& e) {   // InvalidOperation during a motion, invalid values
    reply.ok = 0;
    reply.error = e.what();
    count(counters_.refused_requests, where + "request " + std::to_string(request.request) + " refused: " + e.what());
  }
  reply.utime = utime;
  send_(channels_.config_reply, encode(reply));
}

void RobotServer::step(int64_t utime) {
  command_received_ = session_ && command_.has_value();
  if (command_received_) applied_ = *command_;
  emulator_.step(command_received_ ? &*command_ : nullptr);
  command_.reset();
  if (session_ && !emulator_.in_motion()) {
    session_.reset();
    const rt::RobotState& s = emulator_.state();
    event(s.robot_mode == rt::RobotMode::kReflex ? "control session ended in a reflex: " + emulator_.reflex_reason()
                                                 : "control session finished",
          utime);
  }
}

rt::CycleInfo RobotServer::last_cycle() const { return rt::received_cycle(command_received_, applied_); }

}  // namespace csp::bridge
