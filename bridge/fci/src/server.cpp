#include "csp/fci/server.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "csp/dynamics/arrays.hpp"
#include "framing.hpp"

namespace csp::fci {
namespace {

// Rate limit of the diagnostic lines: the 1st, 10th, 100th, ... of each kind.
bool is_power_of_ten(uint64_t n) {
  while (n >= 10 && n % 10 == 0) n /= 10;
  return n == 1;
}

template <typename T>
std::vector<uint8_t> bytes_of(const T& value) {
  std::vector<uint8_t> bytes(sizeof(T));
  std::memcpy(bytes.data(), &value, sizeof(T));
  return bytes;
}

// The emulator's control mode of a Move request; nullopt for a combination the robot refuses.
// libfranka's torque control (control(torque_callback)) asks for a joint velocity motion generator
// under the external controller and sends zero velocities: the robot checks that setpoint and the
// user's torque drives the arm, which is what the emulator's joint velocity mode with
// kExternalController does. Version 7's kNone (no motion generator) is the pure torque mode.
std::optional<rt::ControlMode> control_mode_of(uint32_t motion_generator, uint32_t controller, Version version) {
  if (controller > static_cast<uint32_t>(MoveControllerMode::kExternalController)) return std::nullopt;
  const bool external = controller == static_cast<uint32_t>(MoveControllerMode::kExternalController);
  switch (static_cast<MoveMotionGeneratorMode>(motion_generator)) {
    case MoveMotionGeneratorMode::kJointPosition: return rt::ControlMode::kJointPosition;
    case MoveMotionGeneratorMode::kJointVelocity: return rt::ControlMode::kJointVelocity;
    case MoveMotionGeneratorMode::kCartesianPosition: return rt::ControlMode::kCartesianPose;
    case MoveMotionGeneratorMode::kCartesianVelocity: return rt::ControlMode::kCartesianVelocity;
    case MoveMotionGeneratorMode::kNone:
      if (version == kFr3Version && external) return rt::ControlMode::kTorque;
      return std::nullopt;
  }
  return std::nullopt;
}

rt::ControllerMode controller_of(MoveControllerMode controller) {
  switch (controller) {
    case MoveControllerMode::kJointImpedance: return rt::ControllerMode::kJointImpedance;
    case MoveControllerMode::kCartesianImpedance: return rt::ControllerMode::kCartesianImpedance;
    case MoveControllerMode::kExternalController: return rt::ControllerMode::kExternalController;
  }
  return rt::ControllerMode::kJointImpedance;
}

StateRobotMode robot_mode_code(rt::RobotMode mode) {
  switch (mode) {
    case rt::RobotMode::kOther: return StateRobotMode::kOther;
    case rt::RobotMode::kIdle: return StateRobotMode::kIdle;
    case rt::RobotMode::kMove: return StateRobotMode::kMove;
    case rt::RobotMode::kGuiding: return StateRobotMode::kGuiding;
    case rt::RobotMode::kReflex: return StateRobotMode::kReflex;
    case rt::RobotMode::kUserStopped: return StateRobotMode::kUserStopped;
    case rt::RobotMode::kAutomaticErrorRecovery: return StateRobotMode::kAutomaticErrorRecovery;
  }
  return StateRobotMode::kOther;
}

std::array<bool, 41> error_flags(const franka::Errors& errors) {
  const rt::ErrorSet set(errors);
  std::array<bool, 41> flags{};
  for (int i = 0; i < rt::kNumErrors; ++i) flags[wire_error_index(static_cast<rt::Error>(i))] = set.flags()[i];
  return flags;
}

// A pose received in a request: a finite rigid transform, else the request is an invalid argument.
Transform pose_of(const std::array<double, 16>& column_major, const char* operation) {
  const std::optional<Transform> pose = rigid_transform_from_matrix(from_array<Eigen::Matrix4d>(column_major));
  if (!pose) throw std::invalid_argument(std::string(operation) + ": expected a rigid transform (4x4 column-major, finite)");
  return *pose;
}

}  // namespace

FciServer::FciServer(rt::Emulator& robot, Version version, ModelLibrary model_library, Diagnostic diagnostic,
                     const rt::CommandFaults& faults)
    : emulator_(robot),
      version_(version),
      model_library_(std::move(model_library)),
      diagnostic_(std::move(diagnostic)),
      channel_(faults) {
  command_code(Command::kConnect, version);   // throws for a version CSP does not serve
}

// ---------------------------------------------------------------------------------------------
// The command port

void FciServer::open_connection(SendTcp send) {
  send_ = std::move(send);
  received_.clear();
  client_udp_port_.reset();
}

void FciServer::close_connection() {
  if (motion_) {
    ++counters_.client_losses;
    diagnose("the client left during a motion: without its commands the robot ends the motion");
  }
  send_ = nullptr;
  received_.clear();
  client_udp_port_.reset();
}

void FciServer::protocol_error(const std::string& what) {
  ++counters_.protocol_errors;
  diagnose("protocol error, connection closed: " + what);
}

bool FciServer::receive_tcp(const uint8_t* data, std::size_t size) {
  const auto problem = [this](const MessageHeader& header) -> std::string {
    if (!client_udp_port_) {
      if (header.command != 0) return "the first message must be Connect (command 0), not command " + std::to_string(header.command);
      if (header.size != request_size(Command::kConnect, version_))
        return "Connect of " + std::to_string(header.size) + " bytes (expected 16)";
      return "";
    }
    const std::optional<Command> command = command_from_code(header.command, version_);
    if (!command || *command == Command::kConnect)
      return "command " + std::to_string(header.command) + " is not a request of FCI version " + std::to_string(version_) + " after Connect";
    if (header.size != request_size(*command, version_))
      return std::string(command_name(*command)) + " of " + std::to_string(header.size) + " bytes (expected " +
             std::to_string(request_size(*command, version_)) + ")";
    return "";
  };
  return take_messages<MessageHeader>(
      received_, data, size, problem, [this](const MessageHeader& header, const uint8_t* payload) { return handle_message(header, payload); },
      [this](const std::string& what) { protocol_error(what); });
}

void FciServer::respond(Command command, uint32_t command_id, Status status, const std::vector<uint8_t>& extra) {
  if (status != Status::kSuccess && status != Status::kMotionStarted && status != Status::kPreempted) {
    ++counters_.refused_requests;
    diagnose(std::string(command_name(command)) + " answered " + status_name(status));
  }
  if (!send_) return;   // the client has gone
  MessageHeader header;
  header.command = command_code(command, version_);
  header.command_id = command_id;
  header.size = static_cast<uint32_t>(sizeof(MessageHeader) + 1 + extra.size());
  std::vector<uint8_t> bytes(header.size);
  std::memcpy(bytes.data(), &header, sizeof(header));
  bytes[sizeof(header)] = status_code(command, status, version_);
  std::copy(extra.begin(), extra.end(), bytes.begin() + sizeof(header) + 1);
  send_(bytes);
}

bool FciServer::handle_connect(const MessageHeader& header, const uint8_t* payload) {
  const auto request = read_payload<ConnectRequest>(payload);
  const std::vector<uint8_t> robot_version = bytes_of(version_);
  if (request.version != version_) {
    ++counters_.refused_versions;
    respond(Command::kConnect, header.command_id, Status::kIncompatibleLibraryVersion, robot_version);
    diagnose("client of FCI version " + std::to_string(request.version) + " refused: this robot speaks version " +
             std::to_string(version_) + (version_ == kPandaVersion ? " (libfranka 0.9)" : " (libfranka 0.13)"));
    return false;
  }
  client_udp_port_ = request.udp_port;
  ++counters_.connections;
  respond(Command::kConnect, header.command_id, Status::kSuccess, robot_version);
  return true;
}

bool FciServer::handle_message(const MessageHeader& header, const uint8_t* payload) {
  const Command command = client_udp_port_ ? *command_from_code(header.command, version_) : Command::kConnect;
  switch (command) {
    case Command::kConnect: return handle_connect(header, payload);
    case Command::kMove: {
      // Answered twice when accepted, as the robot does: MotionStarted now (libfranka's startMotion
      // waits for it), and how the motion ended when it ends (end_motion_if_over).
      const Status status = handle_move(header, read_payload<MoveRequest>(payload));
      respond(command, header.command_id, status == Status::kSuccess ? Status::kMotionStarted : status);
      return true;
    }
    case Command::kStopMove:
      // Nothing to stop is no error: Robot::stop() may be called at any time.
      if (motion_) {
        emulator_.stop_motion();
        stop_requested_ = true;
      }
      respond(command, header.command_id, Status::kSuccess);
      end_motion_if_over();
      return true;
    case Command::kAutomaticErrorRecovery:
      if (motion_) {
        respond(command, header.command_id, Status::kCommandNotPossibleRejected);
      } else {
        emulator_.automatic_error_recovery();
        respond(command, header.command_id, Status::kSuccess);
      }
      return true;
    case Command::kLoadModelLibrary: {
      const auto request = read_payload<LoadModelLibraryRequest>(payload);
      if (request.architecture != 0 || request.system != 0) {   // CSP builds its model for x86-64 Linux
        diagnose("LoadModelLibrary for architecture " + std::to_string(request.architecture) + ", system " +
                 std::to_string(request.system) + ": only x86-64 Linux (0, 0) is served");
        respond(command, header.command_id, Status::kError);
        return true;
      }
      try {
        respond(command, header.command_id, Status::kSuccess, model_library_());
      } catch (const std::exception& e) {
        diagnose(std::string("LoadModelLibrary: ") + e.what());
        respond(command, header.command_id, Status::kError);
      }
      return true;
    }
    case Command::kGetCartesianLimit: {
      // Version 5's virtual walls (Robot::getVirtualWall, deprecated): CSP's robot has none set.
      std::vector<uint8_t> fields = bytes_of(GetCartesianLimitResponse{});
      fields.erase(fields.begin());   // the status byte is respond()'s
      respond(command, header.command_id, Status::kSuccess, fields);
      return true;
    }
    default:
      respond(command, header.command_id, handle_setting(command, payload));
      return true;
  }
}

Status FciServer::handle_move(const MessageHeader& header, const MoveRequest& request) {
  if (motion_) return Status::kCommandNotPossibleRejected;
  const std::optional<rt::ControlMode> mode = control_mode_of(request.motion_generator_mode, request.controller_mode, version_);
  if (!mode) {
    diagnose("Move with motion generator " + std::to_string(request.motion_generator_mode) + " and controller " +
             std::to_string(request.controller_mode) + ": not a combination the robot runs");
    return Status::kInvalidArgumentRejected;
  }
  const auto controller = static_cast<MoveControllerMode>(request.controller_mode);
  try {
    emulator_.start_motion(*mode, controller_of(controller));
  } catch (const rt::InvalidOperation& e) {   // in Reflex mode: recover first
    diagnose(std::string("Move refused: ") + e.what());
    return Status::kCommandNotPossibleRejected;
  }
  motion_ = Motion{header.command_id, static_cast<MoveMotionGeneratorMode>(request.motion_generator_mode), controller, *mode};
  stop_requested_ = false;
  motion_cycle_ = 0;
  ++counters_.motions;
  return Status::kSuccess;
}

Status FciServer::handle_setting(Command command, const uint8_t* payload) {
  if (motion_) return Status::kCommandNotPossibleRejected;   // as libfranka's set* during a motion
  try {
    switch (command) {
      case Command::kSetCollisionBehavior: {
        alignas(8) const auto r = read_payload<CollisionBehaviorRequest>(payload);
        emulator_.set_collision_behavior(rt::collision_behavior(
            r.lower_torque_thresholds_acceleration, r.upper_torque_thresholds_acceleration, r.lower_torque_thresholds_nominal,
            r.upper_torque_thresholds_nominal, r.lower_force_thresholds_acceleration, r.upper_force_thresholds_acceleration,
            r.lower_force_thresholds_nominal, r.upper_force_thresholds_nominal));
        break;
      }
      case Command::kSetJointImpedance: {
        alignas(8) const auto r = read_payload<JointImpedanceRequest>(payload);
        emulator_.set_joint_impedance(from_array<Vector7>(r.K_theta));
        break;
      }
      case Command::kSetCartesianImpedance: {
        alignas(8) const auto r = read_payload<CartesianImpedanceRequest>(payload);
        emulator_.set_cartesian_impedance(from_array<Vector6>(r.K_x));
        break;
      }
      case Command::kSetEEToK: {
        alignas(8) const auto r = read_payload<EEToKRequest>(payload);
        emulator_.set_K(pose_of(r.EE_T_K, "setK"));
        break;
      }
      case Command::kSetNEToEE: {
        alignas(8) const auto r = read_payload<NEToEERequest>(payload);
        emulator_.set_EE(pose_of(r.NE_T_EE, "setEE"));
        break;
      }
      case Command::kSetLoad: {
        alignas(8) const auto r = read_payload<LoadRequest>(payload);
        RigidBodyInertia load;
        load.mass = r.m_load;
        load.com = from_array<Vector3>(r.F_x_Cload);
        load.inertia = from_array<Matrix3>(r.I_load);   // column-major
        emulator_.set_load(load);
        break;
      }
      // Accepted without effect: hand guiding needs a person at the arm (CSP emulates none), and
      // version 5's filters are no longer applied by the robot (libfranka 0.9 deprecates setFilters).
      case Command::kSetGuidingMode:
      case Command::kSetFilters: break;
      default: return Status::kCommandNotPossibleRejected;
    }
  } catch (const rt::InvalidOperation& e) {
    diagnose(std::string(command_name(command)) + ": " + e.what());
    return Status::kCommandNotPossibleRejected;
  } catch (const std::invalid_argument& e) {
    diagnose(std::string(command_name(command)) + ": " + e.what());
    return Status::kInvalidArgumentRejected;
  }
  return Status::kSuccess;
}

// ---------------------------------------------------------------------------------------------
// The 1 kHz exchange

uint64_t FciServer::message_id() const { return static_cast<uint64_t>(emulator_.state().time.toMSec()); }

RobotStatePacket FciServer::state_packet() const {
  const rt::RobotState& s = emulator_.state();
  alignas(8) RobotStatePacket p{};   // (packed: aligned here, its arrays of doubles are)
  p.message_id = message_id();
  p.O_T_EE = s.O_T_EE;
  p.O_T_EE_d = s.O_T_EE_d;
  p.F_T_EE = s.F_T_EE;
  p.EE_T_K = s.EE_T_K;
  p.F_T_NE = s.F_T_NE;
  p.NE_T_EE = s.NE_T_EE;
  p.m_ee = s.m_ee;
  p.I_ee = s.I_ee;
  p.F_x_Cee = s.F_x_Cee;
  p.m_load = s.m_load;
  p.I_load = s.I_load;
  p.F_x_Cload = s.F_x_Cload;
  p.elbow = s.elbow;
  p.elbow_d = s.elbow_d;
  p.tau_J = s.tau_J;
  p.tau_J_d = s.tau_J_d;
  p.dtau_J = s.dtau_J;
  p.q = s.q;
  p.q_d = s.q_d;
  p.dq = s.dq;
  p.dq_d = s.dq_d;
  p.ddq_d = s.ddq_d;
  p.joint_contact = s.joint_contact;
  p.cartesian_contact = s.cartesian_contact;
  p.joint_collision = s.joint_collision;
  p.cartesian_collision = s.cartesian_collision;
  p.tau_ext_hat_filtered = s.tau_ext_hat_filtered;
  p.O_F_ext_hat_K = s.O_F_ext_hat_K;
  p.K_F_ext_hat_K = s.K_F_ext_hat_K;
  p.O_dP_EE_d = s.O_dP_EE_d;
  p.O_ddP_O = s.O_ddP_O;
  p.elbow_c = s.elbow_c;
  p.delbow_c = s.delbow_c;
  p.ddelbow_c = s.ddelbow_c;
  p.O_T_EE_c = s.O_T_EE_c;
  p.O_dP_EE_c = s.O_dP_EE_c;
  p.O_ddP_EE_c = s.O_ddP_EE_c;
  p.theta = s.theta;
  p.dtheta = s.dtheta;
  // The state's mode codes: the Move's motion generator one higher (0 is Idle), its controller as
  // requested; without a motion no controller of the user's choice runs (kOther).
  p.motion_generator_mode = motion_ ? static_cast<StateMotionGeneratorMode>(static_cast<uint32_t>(motion_->motion_generator) + 1)
                                    : StateMotionGeneratorMode::kIdle;
  p.controller_mode = motion_ ? static_cast<StateControllerMode>(motion_->controller) : StateControllerMode::kOther;
  p.errors = error_flags(s.current_errors);
  p.reflex_reason = error_flags(s.last_motion_errors);
  p.robot_mode = robot_mode_code(s.robot_mode);
  p.control_command_success_rate = s.control_command_success_rate;
  return p;
}

void FciServer::receive_udp(const void* data, std::size_t size) {
  const auto reject = [&](uint64_t& counter, const std::string& what) {
    ++counter;
    if (is_power_of_ten(counter)) diagnose("UDP command packet dropped: " + what + " (" + std::to_string(counter) + " so far)");
  };
  const std::optional<RobotCommandValues> packet = decode_robot_command(data, size, version_);
  if (!packet)
    return reject(counters_.rejected_commands, std::to_string(size) + " bytes, expected " + std::to_string(robot_command_size(version_)));
  if (!client_udp_port_ || !motion_) return reject(counters_.rejected_commands, "no motion is running");
  if (packet->message_id != message_id() || command_)
    return reject(counters_.stale_commands, "it answers state " + std::to_string(packet->message_id) + ", the current state is " +
                                                std::to_string(message_id()));
  if (!channel_.delivers(motion_cycle_)) return reject(counters_.injected_losses, "lost by the scenario's faults");
  const RobotCommandValues& m = *packet;
  rt::Command command;
  switch (motion_->mode) {
    case rt::ControlMode::kJointPosition: command.values = from_array<Vector7>(m.q_c); break;
    case rt::ControlMode::kJointVelocity: command.values = from_array<Vector7>(m.dq_c); break;
    case rt::ControlMode::kCartesianPose: command.O_T_EE_c = m.O_T_EE_c; break;
    case rt::ControlMode::kCartesianVelocity: command.O_dP_EE_c = m.O_dP_EE_c; break;
    case rt::ControlMode::kTorque: command.values = from_array<Vector7>(m.tau_J_d); break;
  }
  if (rt::is_cartesian(motion_->mode) && m.valid_elbow) command.elbow = m.elbow_c;
  if (motion_->controller == MoveControllerMode::kExternalController) command.torque = from_array<Vector7>(m.tau_J_d);
  command.motion_finished = motion_->mode == rt::ControlMode::kTorque ? m.torque_command_finished : m.motion_generation_finished;
  command_ = command;
  motion_->commanded = true;
}

void FciServer::step() {
  command_received_ = motion_ && command_.has_value();
  if (command_received_) applied_ = *command_;
  emulator_.step(command_received_ ? &*command_ : nullptr);
  command_.reset();
  if (motion_) ++motion_cycle_;
  end_motion_if_over();
}

// A motion that ended (finished, stopped, or in a reflex) answers its Move request, as the robot
// does: libfranka raises its ControlException from this status and the state's reflex_reason.
void FciServer::end_motion_if_over() {
  if (!motion_ || emulator_.in_motion()) return;
  const Status status = emulator_.state().robot_mode == rt::RobotMode::kReflex ? Status::kReflexAborted
                        : stop_requested_                                      ? Status::kPreempted
                                                                               : Status::kSuccess;
  if (status == Status::kReflexAborted) diagnose("motion ended in a reflex: " + emulator_.reflex_reason());
  respond(Command::kMove, motion_->move_command_id, status);
  motion_.reset();
  stop_requested_ = false;
}

rt::CycleInfo FciServer::last_cycle() const { return rt::received_cycle(command_received_, applied_); }

}  // namespace csp::fci
