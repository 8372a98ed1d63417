// The Franka Hand's server (port 1338) without a transport: the scenario's hand (rt::Hand) stepped
// with the robot's cycles, each command answered when it ends as the hand's server does (libfranka's
// Gripper waits for that answer), a state message about every 100 ms, and the object in its grasp
// carried by the arm (Emulator::set_carried_object): the arm feels what the hand holds.
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

struct GripperCounters {
  uint64_t connections = 0;
  uint64_t refused_versions = 0;
  uint64_t protocol_errors = 0;
  uint64_t commands = 0;            // accepted by the hand
  uint64_t failed_commands = 0;     // refused by the hand (libfranka: "Command failed!")
};

class GripperServer : public PortServer {
 public:
  using Diagnostic = std::function<void(const std::string& line)>;

  GripperServer(rt::Emulator& robot, const rt::HandSettings& hand, Diagnostic diagnostic);

  void open_connection(SendTcp send) override;
  bool receive_tcp(const uint8_t* data, std::size_t size) override;
  void close_connection() override;
  std::optional<uint16_t> client_udp_port() const override { return client_udp_port_; }

  // One robot cycle of the hand: it moves, the commands that ended are answered, and the arm
  // carries what it holds. Returns the state message when one is due.
  std::optional<GripperStatePacket> step();

  const rt::Hand& hand() const { return hand_; }
  const GripperCounters& counters() const { return counters_; }

 private:
  struct Pending {
    uint32_t command_id = 0;
    GripperCommand command = GripperCommand::kStop;
    uint64_t hand_command = 0;   // Hand's number for answer()
  };

  bool handle_message(const GripperMessageHeader& header, const uint8_t* payload);
  void respond(GripperCommand command, uint32_t command_id, uint16_t status, const std::vector<uint8_t>& extra = {});
  void diagnose(const std::string& line) const { if (diagnostic_) diagnostic_(line); }

  rt::Emulator& robot_;
  rt::Hand hand_;
  Diagnostic diagnostic_;
  GripperCounters counters_;
  SendTcp send_;
  std::vector<uint8_t> received_;
  std::optional<uint16_t> client_udp_port_;
  std::vector<Pending> pending_;
  uint64_t published_message_ = 0;
  double carried_mass_ = 0.0;   // what the arm carries for the hand now [kg]
};

}  // namespace csp::fci
