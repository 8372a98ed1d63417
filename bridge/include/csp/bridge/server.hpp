// The robot side of the bridge, independent of the transport: the emulator, the control session
// and the FCI's rule for commands. `csp serve` feeds it messages from LCM; `csp replay` feeds it
// the messages recorded in a log, in the same order, and so reproduces the run bit for bit.
//
// One cycle: state_message() is published -> receive() takes every message that arrives during
// the cycle -> step() applies the command answering this state, or none (lost).
//
// The server takes typed inputs (command(), request()); receive() is the LCM edge that decodes
// bytes into them. Front ends without bytes (the CAN bus) call the typed inputs directly and
// encode only what they log.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "csp/bridge/messages.hpp"
#include "csp/rt/control_loop.hpp"

namespace csp::bridge {

// Messages refused or noticed by the server; it keeps running whatever arrives.
struct ServerCounters {
  uint64_t sessions = 0;
  uint64_t rejected_fingerprint = 0;   // not a type of this channel
  uint64_t rejected_truncated = 0;     // shorter than the type
  uint64_t rejected_oversized = 0;     // longer than the type
  uint64_t rejected_stale = 0;         // does not answer the current state, or a second answer
  uint64_t rejected_wrong_mode = 0;    // a command of another mode than the session's
  uint64_t rejected_no_session = 0;    // a command while no session runs
  uint64_t non_finite_commands = 0;    // passed on: the robot ends the motion in a reflex
  uint64_t refused_requests = 0;       // configuration requests answered with an error
};

class RobotServer {
 public:
  // Where replies and events go (LCM and the log in `csp serve`, nowhere in replay).
  using Send = std::function<void(const std::string& channel, const std::vector<uint8_t>& bytes)>;
  // One line per notable event (rejections are rate-limited).
  using Diagnostic = std::function<void(const std::string& line)>;

  // `robot` is the run's emulated robot (run::Run owns it); the server steps it.
  RobotServer(rt::Emulator& robot, const Channels& channels, Send send, Diagnostic diagnostic);

  int64_t message_id() const { return static_cast<int64_t>(emulator_.state().time.toMSec()); }
  robot_state_t state_message(int64_t utime) const;
  // Handles one message received during the current cycle: decodes it (a message that does not
  // decode is counted and dropped) and passes it to command() or request().
  void receive(const std::string& channel, const void* data, int size, int64_t utime);
  // A command answering the state `received.message_id` in the session's mode.
  void command(const ReceivedCommand& received);
  // A configuration request (START_MOTION, impedances, load, recovery, ...); the reply is sent.
  void request(const config_request_t& request, int64_t utime);
  bool in_session() const { return session_.has_value(); }
  std::optional<rt::ControlMode> session() const { return session_; }
  bool answered() const { return command_.has_value(); }   // this cycle's command arrived
  // Ends the cycle: steps the emulator with the command that answered the state, or none.
  void step(int64_t utime);
  // What the last step applied (a run's observers see it with the state it produced).
  rt::CycleInfo last_cycle() const;

  const rt::Emulator& emulator() const { return emulator_; }
  const ServerCounters& counters() const { return counters_; }

 private:
  void count(uint64_t& counter, const std::string& what);
  // Counts a message that failed decoding (`where` names its channel); true if it decoded.
  bool accepted(Rejection rejection, const std::string& where);
  void event(const std::string& text, int64_t utime);

  rt::Emulator& emulator_;
  Channels channels_;
  Send send_;
  Diagnostic diagnostic_;
  ServerCounters counters_;
  std::optional<rt::ControlMode> session_;
  std::optional<rt::Command> command_;   // the answer to the current state
  bool command_received_ = false;        // the previous step applied a command
  rt::Command applied_;                  // and this one
};

}  // namespace csp::bridge
