// One CANopen node: a joint drive. Its object dictionary values and the CiA 402 state machine,
// composed with the CiA 301 services, each in its own class as CANopenNode has them: NMT slave
// with heartbeat producer, heartbeat consumer, EMCY producer, PDOs and SDO server. No transport
// and no clock of its own: frames come in through receive_*, frames go out into the bus's outbox,
// time through elapse().
#pragma once

#include <cstdint>
#include <vector>

#include "csp/can/cia402.hpp"
#include "csp/can/emcy_producer.hpp"
#include "csp/can/frame.hpp"
#include "csp/can/heartbeat_consumer.hpp"
#include "csp/can/nmt_slave.hpp"
#include "csp/can/object_dictionary.hpp"
#include "csp/can/object_values.hpp"
#include "csp/can/pdo_service.hpp"
#include "csp/can/sdo_server.hpp"
#include "csp/rt/errors.hpp"

namespace csp::can {

// CiA 402 "parameter error": this drive is in operation enabled in another mode of operation than
// other enabled drives of the arm, so the robot runs none of them (one control mode per motion).
inline constexpr uint16_t kEmcyMixedModes = 0x6320;
// Device specific (CiA 301 class 0xFFxx; 0xFF01 + i are libfranka's errors): the robot stopped
// acting on this drive's targets while the drive stays in operation enabled, because the motion
// ended (another drive left operation enabled, or a mode change): statusword bit 12 clears and
// the targets are ignored until all seven drives are in operation enabled in one mode again.
inline constexpr uint16_t kEmcyTargetIgnored = 0xFF00;

// One joint's measured state, SI units (libfranka names).
struct JointMeasurement {
  double q = 0.0;                      // [rad]
  double q_d = 0.0;                    // desired position: where a CSP motion starts [rad]
  double dq = 0.0;                     // [rad/s]
  double tau_J = 0.0;                  // measured link-side torque, gravity included [N m]
  double tau_J_d = 0.0;                // commanded torque without gravity [N m]
  double tau_ext_hat_filtered = 0.0;   // [N m]
};

// One joint's command as latched at a SYNC, SI units.
struct JointCommand {
  int8_t mode = kModeCst;              // 0x6061: 8 CSP, 9 CSV, 10 CST
  bool operation_enabled = false;      // 402 state "operation enabled"
  bool received = false;               // a synchronous RPDO arrived since the previous SYNC
  double target_position = 0.0;        // 0x607A [rad]
  double target_velocity = 0.0;        // 0x60FF + 0x60B1 [rad/s]
  double target_torque = 0.0;          // 0x6071 + 0x60B2, limited to 0x6072 [N m]
  bool gravity_compensation = true;    // 0x2000
};

// The services hold references into the node: it is neither copied nor moved.
class DriveNode final : private ObjectWriter {
 public:
  // Powers the node on: defaults, 402 "switch on disabled", boot-up message into `out`.
  DriveNode(uint8_t node_id, const JointDrive& drive, const Identity& identity, std::vector<Frame>& out);
  DriveNode(const DriveNode&) = delete;
  DriveNode& operator=(const DriveNode&) = delete;

  uint8_t node_id() const { return node_id_; }
  NmtState nmt_state() const { return nmt_.state(); }
  DriveState drive_state() const { return state_; }
  const ObjectTable& table() const { return values_.table(); }
  // The raw value of an entry (tests, diagnostics); the entry must exist.
  int64_t value(uint16_t index, uint8_t subindex) const;

  void nmt_command(uint8_t command);
  void receive_sdo(const Frame& request) { sdo_.receive(request); }
  // A frame on one of this node's RPDO COB-IDs; false if the COB-ID is not one of them.
  bool receive_rpdo(const Frame& frame) { return pdos_.receive(frame); }
  void receive_heartbeat(uint8_t producer, uint8_t /*state*/) { heartbeat_consumer_.receive(producer); }
  void receive_sync(const Frame& frame);   // only checks the length (EMCY 0x8240)
  void elapse(uint32_t microseconds);

  // SYNC, first half: send the TPDOs (the state sampled at this SYNC), then latch the synchronous
  // RPDOs received since the previous SYNC and run the 402 state machine on them.
  void sync_transmit() { pdos_.transmit_sync(); }
  void sync_latch();
  JointCommand command() const;
  // SYNC, second half (and at power-on): the robot's measurement; errors of the whole robot
  // (non-empty = a reflex) fault the drive with one EMCY per error; `mixed_modes` (the enabled
  // drives of the arm are not in one mode) sends EMCY 0x6320 once if this drive is enabled;
  // `motion`: the robot runs a motion on the drives' targets. Statusword bit 12 ("drive follows
  // the target") is set only in operation enabled during a motion; a drive that was followed and
  // stays in operation enabled when the motion ends sends EMCY 0xFF00 (kEmcyTargetIgnored).
  void update(const JointMeasurement& measured, const rt::ErrorSet& errors, bool mixed_modes, bool motion);
  // Fault reset (402 bit 7 rising edge) or a write to 0x2003 since the last call.
  bool take_recovery_request();

 private:
  void reset(bool communication_only);
  void write_measurement();   // measured_ into 0x6062, 0x6064, 0x606C, 0x6074, 0x6077, 0x2001
  // ObjectWriter: an SDO download's or RPDO's value, checked against the entry's range and the
  // PDO rules, then stored.
  uint32_t write(int slot, int64_t value) override;
  void store(int slot, int64_t value);   // stores and applies the side effects
  void set_controlword(uint16_t controlword);
  void set_state(DriveState state);
  void enter_fault(uint16_t emcy_code, int error, uint8_t register_bits);

  uint8_t node_id_;
  JointDrive drive_;
  ObjectValues values_;
  // The CiA 301 services, in the order they depend on one another.
  NmtSlave nmt_;
  HeartbeatConsumer heartbeat_consumer_;
  EmcyProducer emcy_;
  PdoService pdos_;
  SdoServer sdo_;
  // CiA 402.
  DriveState state_ = DriveState::kNotReadyToSwitchOn;
  uint16_t previous_controlword_ = 0;
  bool torque_limited_ = false;        // statusword bit 11: internal limit active
  bool recovery_requested_ = false;
  bool received_since_sync_ = false;
  bool mixed_modes_reported_ = false;  // EMCY 0x6320 sent for the current mix of modes
  bool followed_ = false;              // in operation enabled, and the robot's motion acts on the targets (bit 12)
  JointMeasurement measured_;          // the robot's latest: a reset node reports it, not zeros
  // Slots of the objects the drive logic reads every cycle.
  struct Slots {
    int controlword, statusword, quick_stop_option, mode, mode_display, position_demand, position, velocity, target_torque,
        max_torque, torque_demand, torque_actual, target_position, velocity_offset, torque_offset, target_velocity,
        gravity_compensation, tau_ext, errors_first;
  } s_{};
};

}  // namespace csp::can
