// The robot's side of the FCI, without a transport (like bridge::RobotServer): `csp fci` feeds it
// the bytes of the command port's TCP connection and the UDP command packets, and sends what it
// returns. Nothing here opens a socket, so a test can drive it byte for byte.
//
// One cycle, as on the robot: state_packet() is sent to the client -> receive_udp() takes the
// command packets that arrive during the cycle -> step() applies the one answering this state,
// or none (lost).
//
// The robot outlives its clients: pose, errors and settings stay from one connection to the next.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "csp/fci/port_server.hpp"
#include "csp/fci/protocol.hpp"
#include "csp/rt/control_loop.hpp"

namespace csp::fci {

// What the server refused or noticed; it keeps serving whatever arrives.
struct FciCounters {
  uint64_t connections = 0;            // Connect requests accepted
  uint64_t refused_versions = 0;       // Connect requests of a version the robot does not serve
  uint64_t protocol_errors = 0;        // malformed TCP messages (the connection is closed)
  uint64_t rejected_commands = 0;      // UDP command packets of the wrong size, or without a motion
  uint64_t stale_commands = 0;         // command packets answering another state than the current one
  uint64_t motions = 0;                // Move requests accepted
  uint64_t refused_requests = 0;       // requests answered with another status than Success
  uint64_t client_losses = 0;          // clients gone while a motion ran
  uint64_t injected_losses = 0;        // commands the scenario's `faults:` lost on the way (or made late)
};

class FciServer : public PortServer {
 public:
  // The model library's bytes for LoadModelLibrary (the robot's own model; may throw).
  using ModelLibrary = std::function<std::vector<uint8_t>()>;
  // One line per notable event.
  using Diagnostic = std::function<void(const std::string& line)>;

  // `robot` is the run's emulated robot; `version` the protocol version it speaks (kPandaVersion
  // or kFr3Version: a real Panda serves libfranka 0.9, an FR3 of system 5.5 libfranka 0.13). `faults`: the
  // scenario's network faults, applied to the commands that arrive (loss, latency past the
  // budget, bursts; counted from each motion's start), on top of what the real network does.
  FciServer(rt::Emulator& robot, Version version, ModelLibrary model_library, Diagnostic diagnostic,
            const rt::CommandFaults& faults = {});

  Version version() const { return version_; }

  // PortServer. When the connection closes, a motion still running has lost its controller: as on
  // the robot, its missing commands end it (communication_constraints_violation).
  void open_connection(SendTcp send) override;
  bool receive_tcp(const uint8_t* data, std::size_t size) override;
  void close_connection() override;
  std::optional<uint16_t> client_udp_port() const override { return client_udp_port_; }

  // The state packet of the current cycle (message_id: robot time in ms).
  RobotStatePacket state_packet() const;
  uint64_t message_id() const;
  // A UDP packet from the client: a command answering the current state, or it is counted and dropped.
  void receive_udp(const void* data, std::size_t size);
  bool in_motion() const { return motion_.has_value(); }
  // A motion runs and its commands have begun: libfranka sends a motion's first command only after
  // a state newer than the Move's, so until then a lockstep cycle has nothing to wait for.
  bool commands_flowing() const { return motion_ && motion_->commanded; }
  bool answered() const { return command_.has_value(); }   // this cycle's command arrived
  // Ends the cycle: steps the robot with the command that answered the state, or none; answers
  // the Move request of a motion that ended.
  void step();
  rt::CycleInfo last_cycle() const;

  const rt::Emulator& emulator() const { return emulator_; }
  const FciCounters& counters() const { return counters_; }

 private:
  struct Motion {
    uint32_t move_command_id = 0;
    MoveMotionGeneratorMode motion_generator = MoveMotionGeneratorMode::kJointPosition;
    MoveControllerMode controller = MoveControllerMode::kJointImpedance;
    rt::ControlMode mode = rt::ControlMode::kJointPosition;
    bool commanded = false;   // a command of this motion has arrived
  };

  bool handle_message(const MessageHeader& header, const uint8_t* payload);
  bool handle_connect(const MessageHeader& header, const uint8_t* payload);
  Status handle_move(const MessageHeader& header, const MoveRequest& request);
  Status handle_setting(Command command, const uint8_t* payload);
  void respond(Command command, uint32_t command_id, Status status, const std::vector<uint8_t>& extra = {});
  void protocol_error(const std::string& what);
  void end_motion_if_over();
  void diagnose(const std::string& line) { if (diagnostic_) diagnostic_(line); }

  rt::Emulator& emulator_;
  Version version_;
  ModelLibrary model_library_;
  Diagnostic diagnostic_;
  FciCounters counters_;

  // The connection
  SendTcp send_;
  std::vector<uint8_t> received_;              // bytes of a message not yet complete
  std::optional<uint16_t> client_udp_port_;    // connected (after Connect)

  // The motion and this cycle's command
  rt::CommandChannel channel_;
  std::optional<Motion> motion_;
  uint64_t motion_cycle_ = 0;                  // cycles since the motion began
  bool stop_requested_ = false;                // StopMove during the motion
  std::optional<rt::Command> command_;
  bool command_received_ = false;              // the previous step applied a command
  rt::Command applied_;
};

}  // namespace csp::fci
