#include "csp/fci/device_server.hpp"

#include <algorithm>
#include <cstring>

#include "framing.hpp"

namespace csp::fci {

// The Franka Hand's wire side (research_interface/gripper, version 3).
template <>
struct DeviceProtocol<rt::Hand> {
  static constexpr uint16_t kVersion = kGripperVersion;
  static constexpr const char* kName = "gripper";
  static std::size_t request_size(uint16_t command) { return gripper_request_size(command); }
  static const char* command_name(uint16_t command) { return gripper_command_name(static_cast<GripperCommand>(command)); }
  // Issues a command (not Connect) to the hand; CommandRefused when it refuses.
  static uint64_t issue(rt::Hand& hand, uint16_t command, const uint8_t* payload) {
    switch (static_cast<GripperCommand>(command)) {
      case GripperCommand::kHoming: return hand.homing();
      case GripperCommand::kGrasp: {
        alignas(8) const auto r = read_payload<GraspRequest>(payload);
        return hand.grasp(r.width, r.speed, r.force, r.epsilon_inner, r.epsilon_outer);
      }
      case GripperCommand::kMove: {
        alignas(8) const auto r = read_payload<GripperMoveRequest>(payload);
        return hand.move(r.width, r.speed);
      }
      case GripperCommand::kStop: return hand.stop();
      case GripperCommand::kConnect: break;
    }
    throw rt::CommandRefused("not a command");
  }
  static std::vector<uint8_t> state_message(const rt::HandState& state) {
    GripperStatePacket packet{};
    packet.message_id = static_cast<uint32_t>(state.message_id);
    packet.width = state.width;
    packet.max_width = state.max_width;
    packet.is_grasped = state.is_grasped ? 1 : 0;
    packet.temperature = state.temperature;
    std::vector<uint8_t> bytes(sizeof(packet));
    std::memcpy(bytes.data(), &packet, sizeof(packet));
    return bytes;
  }
};

// The Cobot Pump's wire side (research_interface/vacuum_gripper, version 1).
template <>
struct DeviceProtocol<rt::VacuumPump> {
  static constexpr uint16_t kVersion = kVacuumGripperVersion;
  static constexpr const char* kName = "vacuum gripper";
  static std::size_t request_size(uint16_t command) { return vacuum_request_size(command); }
  static const char* command_name(uint16_t command) { return vacuum_command_name(static_cast<VacuumCommand>(command)); }
  static uint64_t issue(rt::VacuumPump& pump, uint16_t command, const uint8_t* payload) {
    switch (static_cast<VacuumCommand>(command)) {
      case VacuumCommand::kVacuum: {
        const auto r = read_payload<VacuumRequest>(payload);
        if (r.profile > 3) throw rt::CommandRefused("profile " + std::to_string(r.profile) + " is not P0..P3");
        return pump.vacuum(r.vacuum, static_cast<double>(r.timeout_ms) * 1e-3, static_cast<rt::VacuumProfile>(r.profile));
      }
      case VacuumCommand::kDropOff:
        return pump.drop_off(static_cast<double>(read_payload<DropOffRequest>(payload).timeout_ms) * 1e-3);
      case VacuumCommand::kStop: return pump.stop();
      case VacuumCommand::kConnect: break;
    }
    throw rt::CommandRefused("not a command");
  }
  static std::vector<uint8_t> state_message(const rt::VacuumState& state) {
    VacuumStatePacket packet{};
    packet.message_id = static_cast<uint32_t>(state.message_id);
    packet.in_control_range = state.in_control_range ? 1 : 0;
    packet.part_detached = state.part_detached ? 1 : 0;
    packet.part_present = state.part_present ? 1 : 0;
    packet.device_status = 0;   // green: CSP's pump does not wear
    packet.actual_power = state.actual_power;
    packet.vacuum = state.vacuum;
    std::vector<uint8_t> bytes(sizeof(packet));
    std::memcpy(bytes.data(), &packet, sizeof(packet));
    return bytes;
  }
};

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

constexpr uint16_t kConnectCommand = 0;   // both devices' Connect
constexpr uint16_t kIncompatibleLibraryVersion = 1;

}  // namespace

template <typename Device>
DeviceServer<Device>::DeviceServer(rt::Emulator& robot, Device device, Diagnostic diagnostic)
    : robot_(robot), device_(std::move(device)), diagnostic_(std::move(diagnostic)) {}

template <typename Device>
void DeviceServer<Device>::diagnose(const std::string& line) const {
  if (diagnostic_) diagnostic_(std::string(DeviceProtocol<Device>::kName) + ": " + line);
}

template <typename Device>
void DeviceServer<Device>::open_connection(SendTcp send) {
  send_ = std::move(send);
  received_.clear();
  client_udp_port_.reset();
}

template <typename Device>
void DeviceServer<Device>::close_connection() {
  send_ = nullptr;
  received_.clear();
  client_udp_port_.reset();
  pending_.clear();   // the device finishes what it does; nobody waits for the answers
}

template <typename Device>
bool DeviceServer<Device>::receive_tcp(const uint8_t* data, std::size_t size) {
  using Protocol = DeviceProtocol<Device>;
  const auto problem = [this](const GripperMessageHeader& header) -> std::string {
    const bool connect = header.command == kConnectCommand;
    if (!client_udp_port_ && !connect) return "the first message must be Connect, not command " + std::to_string(header.command);
    if (client_udp_port_ && connect) return "a second Connect";
    const std::size_t expected = Protocol::request_size(header.command);
    if (expected == 0) return "command " + std::to_string(header.command) + " is not a request of this device";
    if (header.size != expected)
      return std::string(Protocol::command_name(header.command)) + " of " + std::to_string(header.size) + " bytes (expected " +
             std::to_string(expected) + ")";
    return "";
  };
  return take_messages<GripperMessageHeader>(
      received_, data, size, problem,
      [this](const GripperMessageHeader& header, const uint8_t* payload) { return handle_message(header, payload); },
      [this](const std::string& what) {
        ++counters_.protocol_errors;
        diagnose("protocol error, connection closed: " + what);
      });
}

template <typename Device>
void DeviceServer<Device>::respond(uint16_t command, uint32_t command_id, uint16_t status, const std::vector<uint8_t>& extra) {
  if (!send_) return;
  GripperMessageHeader header;
  header.command = command;
  header.command_id = command_id;
  header.size = static_cast<uint32_t>(sizeof(header) + sizeof(status) + extra.size());
  std::vector<uint8_t> bytes(header.size);
  std::memcpy(bytes.data(), &header, sizeof(header));
  std::memcpy(bytes.data() + sizeof(header), &status, sizeof(status));
  std::copy(extra.begin(), extra.end(), bytes.begin() + sizeof(header) + sizeof(status));
  send_(bytes);
}

template <typename Device>
bool DeviceServer<Device>::handle_message(const GripperMessageHeader& header, const uint8_t* payload) {
  using Protocol = DeviceProtocol<Device>;
  if (header.command == kConnectCommand) {
    const auto request = read_payload<GripperConnectRequest>(payload);
    std::vector<uint8_t> version(sizeof(Protocol::kVersion));
    std::memcpy(version.data(), &Protocol::kVersion, sizeof(Protocol::kVersion));
    if (request.version != Protocol::kVersion) {
      ++counters_.refused_versions;
      respond(header.command, header.command_id, kIncompatibleLibraryVersion, version);
      diagnose("client of version " + std::to_string(request.version) + " refused: the device speaks version " +
               std::to_string(Protocol::kVersion));
      return false;
    }
    client_udp_port_ = request.udp_port;
    ++counters_.connections;
    respond(header.command, header.command_id, static_cast<uint16_t>(GripperStatus::kSuccess), version);
    return true;
  }
  try {
    const uint64_t device_command = Protocol::issue(device_, header.command, payload);
    ++counters_.commands;
    pending_.push_back({header.command_id, header.command, device_command});
  } catch (const rt::CommandRefused& refused) {
    ++counters_.failed_commands;
    diagnose(std::string(Protocol::command_name(header.command)) + " failed: " + refused.what());
    respond(header.command, header.command_id, static_cast<uint16_t>(GripperStatus::kFail));
  }
  return true;
}

template <typename Device>
std::optional<std::vector<uint8_t>> DeviceServer<Device>::step() {
  device_.step(rt::kDeltaT);
  std::erase_if(pending_, [this](const Pending& p) {
    const rt::CommandStatus status = device_.answer(p.device_command);
    if (status == rt::CommandStatus::kRunning) return false;
    respond(p.command, p.command_id, status_of(status));
    return true;
  });
  const RigidBodyInertia carried = device_.carried_object();
  if (carried.mass != carried_mass_) {   // held or released (the object's mass is its only change)
    robot_.set_carried_object(carried);
    carried_mass_ = carried.mass;
  }
  const auto& state = device_.published_state();
  if (state.message_id == published_message_) return std::nullopt;
  published_message_ = state.message_id;
  return DeviceProtocol<Device>::state_message(state);
}

template class DeviceServer<rt::Hand>;
template class DeviceServer<rt::VacuumPump>;

}  // namespace csp::fci
