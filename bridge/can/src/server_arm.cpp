#include "csp/can/server_arm.hpp"

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/arrays.hpp"

namespace csp::can {
namespace {

std::optional<rt::ControlMode> control_mode_of(int8_t mode) {
  switch (mode) {
    case kModeCst: return rt::ControlMode::kTorque;
    case kModeCsp: return rt::ControlMode::kJointPosition;
    case kModeCsv: return rt::ControlMode::kJointVelocity;
    default: return std::nullopt;
  }
}

const char* mode_abbreviation(int8_t mode) {
  switch (mode) {
    case kModeCst: return "CST";
    case kModeCsp: return "CSP";
    case kModeCsv: return "CSV";
    default: return "?";
  }
}

// "joints 2, 3, 7": the joints whose operation_enabled is `enabled`.
std::string joints_where(const ArmCommand& command, bool enabled) {
  std::string text;
  for (int j = 0; j < kJoints; ++j)
    if (command.joints[j].operation_enabled == enabled) text += (text.empty() ? "" : ", ") + std::to_string(j + 1);
  return (text.find(',') == std::string::npos ? "joint " : "joints ") + text;
}

// "joint 1 CST, 2 CST, 7 CSP": the enabled joints and their modes.
std::string enabled_modes(const ArmCommand& command) {
  std::string text;
  for (int j = 0; j < kJoints; ++j) {
    if (!command.joints[j].operation_enabled) continue;
    text += (text.empty() ? "joint " : ", ") + std::to_string(j + 1) + " " + mode_abbreviation(command.joints[j].mode);
  }
  return text;
}

}  // namespace

ServerArm::ServerArm(rt::Emulator& robot, const rt::Scenario& scenario, const std::string& log_path,
                     bridge::RobotServer::Diagnostic diagnostic)
    : log_(log_path.empty() ? nullptr : std::make_unique<bridge::LogWriter>(log_path)),
      diagnostic_(std::move(diagnostic)),
      server_(
          robot, channels_,
          [this](const std::string& channel, const std::vector<uint8_t>& bytes) {
            if (log_) log_->write(channel, bytes, bridge::now_utime());
          },
          diagnostic_) {
  if (log_) log_->write(channels_.scenario, bridge::encode(bridge::scenario_message(scenario, "")), bridge::now_utime());
  log_state();
}

// The server takes the request as it is; the log gets it encoded, as `csp serve` logs what it
// receives, so that `csp replay` re-simulates a CAN session like an LCM one.
void ServerArm::request(int8_t kind, rt::ControlMode mode) {
  config_request_t r{};
  r.utime = bridge::now_utime();
  r.request_id = ++request_id_;
  r.request = kind;
  r.control_mode = bridge::control_mode_code(mode);
  if (log_) log_->write(channels_.config, bridge::encode(r), r.utime);
  server_.request(r, r.utime);
}

void ServerArm::send_command(rt::ControlMode mode, const rt::Command& command) {
  const bridge::ReceivedCommand received{mode, server_.message_id(), command};
  const int64_t utime = bridge::now_utime();
  if (log_) log_->write(channels_.command, bridge::encode_command(mode, received.message_id, command, utime), utime);
  server_.command(received);
  last_command_ = command;
}

void ServerArm::log_state() {
  if (!log_) return;
  const int64_t utime = bridge::now_utime();
  log_->write(channels_.state, bridge::encode(server_.state_message(utime)), utime);
  ++state_messages_;
}

// The server's event record (what RobotServer writes for its own events); replay skips events.
void ServerArm::log_event(const std::string& text) {
  if (!log_) return;
  event_t e;
  e.utime = bridge::now_utime();
  e.time = server_.message_id();
  e.text = text;
  log_->write(channels_.event, bridge::encode(e), e.utime);
}

void ServerArm::log_error(const std::string& text) {
  log_event("error: " + text);
  diagnostic_("error: " + text);
}

rt::Command ServerArm::command_values(rt::ControlMode mode, const ArmCommand& command) {
  rt::Command c;
  bool subtract_gravity = false;
  for (int j = 0; j < kJoints; ++j) {
    const JointCommand& joint = command.joints[j];
    if (mode == rt::ControlMode::kTorque) c.values[j] = joint.target_torque;
    if (mode == rt::ControlMode::kJointPosition) c.values[j] = joint.target_position;
    if (mode == rt::ControlMode::kJointVelocity) c.values[j] = joint.target_velocity;
    subtract_gravity = subtract_gravity || (mode == rt::ControlMode::kTorque && !joint.gravity_compensation);
  }
  if (subtract_gravity) {
    // The master's torque holds the arm itself: take off the gravity the robot adds (its own
    // model at the measured q), joint by joint.
    Vector7 gravity;
    gravity_torque(server_.emulator().internal_model(), data_, from_array<Vector7>(server_.emulator().state().q), gravity);
    for (int j = 0; j < kJoints; ++j)
      if (!command.joints[j].gravity_compensation) c.values[j] -= gravity[j];
  }
  return c;
}

ArmState ServerArm::cycle(const ArmCommand& command) {
  const rt::RobotState& before = server_.emulator().state();
  if (command.error_recovery && !server_.in_session() && (bool(before.current_errors) || before.robot_mode == rt::RobotMode::kReflex)) {
    request(config_request_t::AUTOMATIC_ERROR_RECOVERY, rt::ControlMode::kTorque);
    ++counters_.recoveries;
  }

  bool all_enabled = true, mixed = false;
  std::optional<int8_t> enabled_mode;   // the mode of the first joint in operation enabled
  for (const JointCommand& joint : command.joints) {
    all_enabled = all_enabled && joint.operation_enabled;
    if (!joint.operation_enabled) continue;
    if (!enabled_mode) enabled_mode = joint.mode;
    mixed = mixed || joint.mode != *enabled_mode;
  }
  if (mixed && !mixed_before_) {
    ++counters_.mixed_modes;
    log_error("the joints in operation enabled are in different modes of operation (" + enabled_modes(command) +
              "): no motion runs, the robot takes one control mode per motion; EMCY 0x6320 from each");
  }
  mixed_before_ = mixed;
  const std::optional<rt::ControlMode> mode = all_enabled && !mixed ? control_mode_of(*enabled_mode) : std::nullopt;
  if (mode && !all_enabled_before_ && !server_.in_session()) {
    // The drives were just enabled: one START_MOTION (refused ones are not retried until the
    // master disables and enables again).
    request(config_request_t::START_MOTION, *mode);
    ++counters_.motions;
    // Until the first command: hold still where the arm is.
    last_command_ = rt::Command{};
    if (mode == rt::ControlMode::kJointPosition) last_command_.values = from_array<Vector7>(before.q);
  }
  all_enabled_before_ = all_enabled;

  if (server_.in_session()) {
    const rt::ControlMode session = *server_.session();
    if (!all_enabled || mode != session) {
      rt::Command finish = last_command_;   // the master stopped the motion: libfranka's MotionFinished
      finish.motion_finished = true;
      send_command(session, finish);
      if (enabled_mode && !mixed) {   // drives stay in operation enabled with nothing acting on their targets (a mix has its own event)
        ++counters_.abandoned_motions;
        const std::string cause = all_enabled ? "the drives changed their mode of operation"
                                              : joints_where(command, false) + " left operation enabled";
        log_error(cause + ": the motion ended; " + joints_where(command, true) +
                  " stay in operation enabled with their targets ignored (statusword bit 12 clear, EMCY 0xFF00 from each) "
                  "until all seven drives enter operation enabled in one mode again");
      }
    } else if (command.complete) {
      send_command(session, command_values(session, command));
    }
  }
  server_.step(bridge::now_utime());
  log_state();
  ArmState state = measured();
  state.mixed_modes = mixed;
  state.motion = mode && server_.in_session() && *server_.session() == *mode;
  if (enabled_mode && !state.motion) ++counters_.ignored_cycles;
  return state;
}

ArmState ServerArm::measured() const {
  const rt::RobotState& s = server_.emulator().state();
  ArmState state;
  for (int j = 0; j < kJoints; ++j)
    state.joints[j] = JointMeasurement{s.q[j], s.q_d[j], s.dq[j], s.tau_J[j], s.tau_J_d[j], s.tau_ext_hat_filtered[j]};
  state.errors = rt::ErrorSet(s.current_errors);
  return state;
}

}  // namespace csp::can
