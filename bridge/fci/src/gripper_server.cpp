#include "csp/fci/gripper_server.hpp"

#include <cstring>

#include "framing.hpp"

namespace csp::fci {
namespace {

uint16_t status_of(rt::CommandStatus status) {
  switch (status) {
    case rt::CommandStatus::kSuccess: return static_cast<uint16_t>(GripperStatus::kSuccess);
    case rt::CommandStatus::kUnsuccessful: return static_cast<uint16_t>(GripperStatus::kUnsuccessful);
    case rt::CommandStatus::kAborted: return static_cast<uint16_t>(GripperStatus::kAborted);
    case rt::CommandStatus::kRunning: break;
  }
  return static_cast<uint16_t>(GripperStatus::kFail);
}

}  // namespace

GripperServer::GripperServer(rt::Emulator& robot, const rt::HandSettings& hand, Diagnostic diagnostic)
    : robot_(robot), hand_(hand), diagnostic_(std::move(diagnostic)) {}

void GripperServer::open_connection(SendTcp send) {
  send_ = std::move(send);
  received_.clear();
  client_udp_port_.reset();
}

void GripperServer::close_connection() {
  send_ = nullptr;
  received_.clear();
  client_udp_port_.reset();
  pending_.clear();   // the hand finishes what it does; nobody waits for the answers
}

bool GripperServer::receive_tcp(const uint8_t* data, std::size_t size) {
  const auto problem = [this](const GripperMessageHeader& header) -> std::string {
    const bool connect = header.command == static_cast<uint16_t>(GripperCommand::kConnect);
    if (!client_udp_port_ && !connect) return "the first message must be Connect, not command " + std::to_string(header.command);
    if (client_udp_port_ && connect) return "a second Connect";
    const std::size_t expected = gripper_request_size(header.command);
    if (expected == 0) return "command " + std::to_string(header.command) + " is not a gripper request";
    if (header.size != expected)
      return std::string(gripper_command_name(static_cast<GripperCommand>(header.command))) + " of " + std::to_string(header.size) +
             " bytes (expected " + std::to_string(expected) + ")";
    return "";
  };
  return take_messages<GripperMessageHeader>(
      received_, data, size, problem,
      [this](const GripperMessageHeader& header, const uint8_t* payload) { return handle_message(header, payload); },
      [this](const std::string& what) {
        ++counters_.protocol_errors;
        diagnose("gripper: protocol error, connection closed: " + what);
      });
}

void GripperServer::respond(GripperCommand command, uint32_t command_id, uint16_t status, const std::vector<uint8_t>& extra) {
  if (!send_) return;
  GripperMessageHeader header;
  header.command = static_cast<uint16_t>(command);
  header.command_id = command_id;
  header.size = static_cast<uint32_t>(sizeof(header) + sizeof(status) + extra.size());
  std::vector<uint8_t> bytes(header.size);
  std::memcpy(bytes.data(), &header, sizeof(header));
  std::memcpy(bytes.data() + sizeof(header), &status, sizeof(status));
  std::copy(extra.begin(), extra.end(), bytes.begin() + sizeof(header) + sizeof(status));
  send_(bytes);
}

bool GripperServer::handle_message(const GripperMessageHeader& header, const uint8_t* payload) {
  const auto command = static_cast<GripperCommand>(header.command);
  if (command == GripperCommand::kConnect) {
    const auto request = read_payload<GripperConnectRequest>(payload);
    std::vector<uint8_t> version(sizeof(kGripperVersion));
    std::memcpy(version.data(), &kGripperVersion, sizeof(kGripperVersion));
    if (request.version != kGripperVersion) {
      ++counters_.refused_versions;
      respond(command, header.command_id, 1, version);   // kIncompatibleLibraryVersion
      diagnose("gripper: client of version " + std::to_string(request.version) + " refused: the hand speaks version 3");
      return false;
    }
    client_udp_port_ = request.udp_port;
    ++counters_.connections;
    respond(command, header.command_id, static_cast<uint16_t>(GripperStatus::kSuccess), version);
    return true;
  }
  try {
    uint64_t hand_command = 0;
    switch (command) {
      case GripperCommand::kHoming: hand_command = hand_.homing(); break;
      case GripperCommand::kGrasp: {
        const auto r = read_payload<GraspRequest>(payload);
        hand_command = hand_.grasp(r.width, r.speed, r.force, r.epsilon_inner, r.epsilon_outer);
        break;
      }
      case GripperCommand::kMove: {
        const auto r = read_payload<GripperMoveRequest>(payload);
        hand_command = hand_.move(r.width, r.speed);
        break;
      }
      case GripperCommand::kStop: hand_command = hand_.stop(); break;
      case GripperCommand::kConnect: break;
    }
    ++counters_.commands;
    pending_.push_back({header.command_id, command, hand_command});
  } catch (const rt::CommandRefused& refused) {
    ++counters_.failed_commands;
    diagnose(std::string("gripper: ") + gripper_command_name(command) + " failed: " + refused.what());
    respond(command, header.command_id, static_cast<uint16_t>(GripperStatus::kFail));
  }
  return true;
}

std::optional<GripperStatePacket> GripperServer::step() {
  hand_.step(rt::kDeltaT);
  std::erase_if(pending_, [this](const Pending& p) {
    const rt::CommandStatus status = hand_.answer(p.hand_command);
    if (status == rt::CommandStatus::kRunning) return false;
    respond(p.command, p.command_id, status_of(status));
    return true;
  });
  const RigidBodyInertia carried = hand_.carried_object();
  if (carried.mass != carried_mass_) {   // grasped or released (the object's mass is its only change)
    robot_.set_carried_object(carried);
    carried_mass_ = carried.mass;
  }
  const rt::HandState& state = hand_.published_state();
  if (state.message_id == published_message_) return std::nullopt;
  published_message_ = state.message_id;
  GripperStatePacket packet{};
  packet.message_id = static_cast<uint32_t>(state.message_id);
  packet.width = state.width;
  packet.max_width = state.max_width;
  packet.is_grasped = state.is_grasped ? 1 : 0;
  packet.temperature = state.temperature;
  return packet;
}

}  // namespace csp::fci
