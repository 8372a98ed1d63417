// The servers of the robot's end-effector devices, without a transport: the Franka Hand (port
// 1338, rt::Hand) and the Cobot Pump (port 1339, rt::VacuumPump). Both speak the same shape of
// protocol: a 16-bit command code, Connect with the device's version, each command answered when it
// ends as the device's server does (libfranka's Gripper and VacuumGripper wait for that answer:
// Success, Unsuccessful, Aborted by a newer command, Fail for a command the device refuses), and a
// state message about every 100 ms. The device steps with the robot's cycles, and the arm carries
// what it holds (Emulator::set_carried_object).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "csp/fci/port_server.hpp"
#include "csp/fci/protocol.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/hand.hpp"

namespace csp::fci {

struct DeviceCounters {
  uint64_t connections = 0;
  uint64_t refused_versions = 0;
  uint64_t protocol_errors = 0;
  uint64_t commands = 0;            // accepted by the device
  uint64_t failed_commands = 0;     // refused by the device (libfranka: "Command failed!")
};

// What `csp fci` needs of either device's server.
class DeviceServerBase : public PortServer {
 public:
  // One robot cycle of the device: it moves, the commands that ended are answered, the arm
  // carries what it holds. Returns the state message's bytes when one is due.
  virtual std::optional<std::vector<uint8_t>> step() = 0;
  virtual const DeviceCounters& counters() const = 0;
};

// The wire side of one device (version, commands, payloads, state message): gripper and vacuum
// gripper specializations in device_server.cpp.
template <typename Device>
struct DeviceProtocol;

template <typename Device>
class DeviceServer : public DeviceServerBase {
 public:
  using Diagnostic = std::function<void(const std::string& line)>;

  DeviceServer(rt::Emulator& robot, Device device, Diagnostic diagnostic);

  void open_connection(SendTcp send) override;
  bool receive_tcp(const uint8_t* data, std::size_t size) override;
  void close_connection() override;
  std::optional<uint16_t> client_udp_port() const override { return client_udp_port_; }
  std::optional<std::vector<uint8_t>> step() override;
  const DeviceCounters& counters() const override { return counters_; }

  const Device& device() const { return device_; }

 private:
  struct Pending {
    uint32_t command_id = 0;
    uint16_t command = 0;
    uint64_t device_command = 0;   // the device's number for answer()
  };

  bool handle_message(const GripperMessageHeader& header, const uint8_t* payload);
  void respond(uint16_t command, uint32_t command_id, uint16_t status, const std::vector<uint8_t>& extra = {});
  void diagnose(const std::string& line) const;

  rt::Emulator& robot_;
  Device device_;
  Diagnostic diagnostic_;
  DeviceCounters counters_;
  SendTcp send_;
  std::vector<uint8_t> received_;
  std::optional<uint16_t> client_udp_port_;
  std::vector<Pending> pending_;
  uint64_t published_message_ = 0;
  double carried_mass_ = 0.0;   // what the arm carries for the device now [kg]
};

using GripperServer = DeviceServer<rt::Hand>;
using VacuumGripperServer = DeviceServer<rt::VacuumPump>;

}  // namespace csp::fci
