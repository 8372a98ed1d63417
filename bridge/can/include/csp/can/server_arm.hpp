// The Arm behind the CAN drives in `csp can serve`: bridge's transport-free RobotServer, the one
// LCM feeds. Each SYNC becomes one server cycle with the inputs an LCM controller would have
// sent (START_MOTION, one command answering the state, AUTOMATIC_ERROR_RECOVERY), passed typed;
// the session log holds them encoded as LCM messages, so that `csp replay` re-simulates a CAN
// session bit for bit.
//
// Franka's semantics on top of CiA 402 (docs/can.md, "The robot behind the drives"):
// - all seven joints reaching operation enabled in one mode start a motion: CST (10) -> torque
//   mode (without gravity; 0x2000 = 0: the master's torque includes gravity), CSP (8) -> joint
//   position mode, CSV (9) -> joint velocity mode, with every check the emulator makes;
// - joints in operation enabled in different modes run no motion: an error event in the session
//   log, and ArmState::mixed_modes (EMCY 0x6320 from those drives);
// - a joint leaving operation enabled, or a mode change, finishes the motion; drives left in
//   operation enabled then clear statusword bit 12 and send EMCY 0xFF00 (their targets are
//   ignored), and the session log gets an error event naming them;
// - a cycle without every enabled joint's RPDO is lost: 20 in a row give the reflex
//   communication_constraints_violation; any reflex faults every drive (EMCY, 402 fault);
// - a fault reset (or 0x2003) is libfranka's automaticErrorRecovery().
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/server.hpp"
#include "csp/can/drive_bus.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::can {

struct ServerArmCounters {
  uint64_t motions = 0;           // START_MOTION requests sent
  uint64_t mixed_modes = 0;       // times the enabled joints came to be in different modes (no motion)
  uint64_t recoveries = 0;        // AUTOMATIC_ERROR_RECOVERY requests sent
  uint64_t abandoned_motions = 0; // motions that ended while drives stayed in operation enabled
  uint64_t ignored_cycles = 0;    // cycles with a drive in operation enabled whose targets no motion ran
};

class ServerArm : public Arm {
 public:
  // `robot`: the run's emulated robot, of `scenario`. `log_path` empty: no session log.
  // `diagnostic` gets the server's notable events.
  ServerArm(rt::Emulator& robot, const rt::Scenario& scenario, const std::string& log_path,
            bridge::RobotServer::Diagnostic diagnostic);

  ArmState cycle(const ArmCommand& command) override;
  ArmState measured() const override;

  const bridge::RobotServer& server() const { return server_; }
  const ServerArmCounters& counters() const { return counters_; }
  bridge::LogWriter* log() { return log_.get(); }
  // An event record in the session log (replay skips events), e.g. the session's frame counts.
  void log_event(const std::string& text);
  uint64_t state_messages() const { return state_messages_; }

 private:
  void request(int8_t kind, rt::ControlMode mode);
  void send_command(rt::ControlMode mode, const rt::Command& command);
  void log_state();
  void log_error(const std::string& text);   // an event record (CSP_EVENT) and a diagnostic line
  rt::Command command_values(rt::ControlMode mode, const ArmCommand& command);

  bridge::Channels channels_;
  std::unique_ptr<bridge::LogWriter> log_;
  bridge::RobotServer::Diagnostic diagnostic_;
  bridge::RobotServer server_;
  ServerArmCounters counters_;
  bool all_enabled_before_ = false;   // the previous cycle had every joint in operation enabled
  bool mixed_before_ = false;         // the previous cycle's enabled joints were in different modes
  rt::Command last_command_;          // what a finishing command repeats
  int64_t request_id_ = 0;
  uint64_t state_messages_ = 0;
  Data data_;                         // gravity of the robot's model (0x2000 = 0)
};

}  // namespace csp::can
