// One CANopen node: a joint drive. Object dictionary values, the SDO server (expedited and
// segmented), NMT slave with heartbeat producer and consumer, PDOs (mappable by SDO as a CiA 302
// master does it), the CiA 402 state machine and EMCY. No transport and no clock of its own:
// frames come in through receive_*, frames go out into the bus's outbox, time through elapse().
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "csp/can/cia402.hpp"
#include "csp/can/frame.hpp"
#include "csp/can/object_dictionary.hpp"
#include "csp/rt/errors.hpp"

namespace csp::can {

enum class NmtState : uint8_t { kInitialising = 0x00, kStopped = 0x04, kOperational = 0x05, kPreOperational = 0x7F };
const char* nmt_state_name(NmtState state);

// NMT command specifiers (first byte of COB-ID 0x000).
inline constexpr uint8_t kNmtStart = 0x01, kNmtStop = 0x02, kNmtEnterPreOperational = 0x80, kNmtResetNode = 0x81,
                         kNmtResetCommunication = 0x82;

// SDO abort codes (CiA 301 table "SDO abort codes"; the same numbers in python-canopen's
// canopen/sdo/exceptions.py).
namespace abort {
inline constexpr uint32_t kToggleBit = 0x05030000, kUnknownCommand = 0x05040001, kUnsupportedAccess = 0x06010000,
                          kWriteOnly = 0x06010001, kReadOnly = 0x06010002, kNoObject = 0x06020000,
                          kNotMappable = 0x06040041, kPdoLength = 0x06040042, kIncompatible = 0x06040043,
                          kLengthMismatch = 0x06070010, kLengthTooHigh = 0x06070012, kLengthTooLow = 0x06070013,
                          kNoSubindex = 0x06090011, kInvalidValue = 0x06090030, kValueTooHigh = 0x06090031,
                          kValueTooLow = 0x06090032, kDeviceState = 0x08000022;
}

// EMCY codes of the communication layer (CiA 301 / CiA 302 emergency error codes).
inline constexpr uint16_t kEmcyErrorReset = 0x0000, kEmcyHeartbeat = 0x8130, kEmcyPdoLength = 0x8210,
                          kEmcyPdoLengthExceeded = 0x8220, kEmcySyncLength = 0x8240, kEmcyRpdoTimeout = 0x8250;
// CiA 402 "parameter error": this drive is in operation enabled in another mode of operation than
// other enabled drives of the arm, so the robot runs none of them (one control mode per motion).
inline constexpr uint16_t kEmcyMixedModes = 0x6320;

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

class DriveNode {
 public:
  // Powers the node on: defaults, 402 "switch on disabled", boot-up message into `out`.
  DriveNode(uint8_t node_id, const JointDrive& drive, const Identity& identity, std::vector<Frame>& out);

  uint8_t node_id() const { return node_id_; }
  NmtState nmt_state() const { return nmt_; }
  DriveState drive_state() const { return state_; }
  const ObjectTable& table() const { return table_; }
  // The raw value of an entry (tests, diagnostics); the entry must exist.
  int64_t value(uint16_t index, uint8_t subindex) const;

  void nmt_command(uint8_t command);
  void receive_sdo(const Frame& request);
  // A frame on one of this node's RPDO COB-IDs; false if the COB-ID is not one of them.
  bool receive_rpdo(const Frame& frame);
  void receive_heartbeat(uint8_t producer, uint8_t state);
  void receive_sync(const Frame& frame);   // only checks the length (EMCY 0x8240)
  void elapse(uint32_t microseconds);

  // SYNC, first half: send the TPDOs (the state sampled at this SYNC), then latch the synchronous
  // RPDOs received since the previous SYNC and run the 402 state machine on them.
  void sync_transmit();
  void sync_latch();
  JointCommand command() const;
  // SYNC, second half (and at power-on): the robot's measurement; errors of the whole robot
  // (non-empty = a reflex) fault the drive with one EMCY per error; `mixed_modes` (the enabled
  // drives of the arm are not in one mode) sends EMCY 0x6320 once if this drive is enabled.
  void update(const JointMeasurement& measured, const rt::ErrorSet& errors, bool mixed_modes);
  // Fault reset (402 bit 7 rising edge) or a write to 0x2003 since the last call.
  bool take_recovery_request();

 private:
  struct MappedValue {
    int slot;
    int bytes;
  };
  struct Pdo {
    int communication_index;   // 0x1400+i / 0x1800+i
    bool receive;
    std::vector<MappedValue> map;
    int bytes = 0;
    uint32_t sync_count = 0;
    bool pending = false;      // synchronous RPDO waiting for the next SYNC
    std::array<uint8_t, 8> data{};
  };
  struct SdoTransfer {
    enum class Kind { kNone, kDownload, kUpload } kind = Kind::kNone;
    int slot = -1;
    bool toggle = false;
    std::vector<uint8_t> data;
    size_t offset = 0;
  };

  void reset(bool communication_only);
  void write_measurement();   // measured_ into 0x6062, 0x6064, 0x606C, 0x6074, 0x6077, 0x2001
  void boot_up();
  int slot(uint16_t index, uint8_t subindex) const;
  std::vector<uint8_t> read_bytes(int slot) const;
  // Validates and stores an SDO write; returns 0 or the abort code.
  uint32_t sdo_write(int slot, const uint8_t* bytes, size_t size);
  uint32_t check_pdo_parameter(int slot, int64_t value) const;
  uint32_t build_map(Pdo& pdo, int count, std::vector<MappedValue>* map) const;
  void store(int slot, int64_t value);   // stores and applies the side effects
  void rebuild_pdos();
  void apply_rpdo(const Pdo& pdo, const uint8_t* data);
  void set_controlword(uint16_t controlword);
  void set_state(DriveState state);
  void enter_fault(uint16_t emcy_code, int error, uint8_t register_bits);
  void send_emcy(uint16_t code, int error);
  void sdo_abort(uint16_t index, uint8_t subindex, uint32_t code);
  void send_sdo(const std::array<uint8_t, 8>& bytes);
  void send(uint32_t id, std::initializer_list<uint8_t> bytes);
  uint32_t cob_id(const Pdo& pdo) const;
  bool pdo_valid(const Pdo& pdo) const;

  uint8_t node_id_;
  JointDrive drive_;
  ObjectTable table_;
  std::vector<Frame>& out_;
  std::vector<int64_t> values_;
  NmtState nmt_ = NmtState::kInitialising;
  DriveState state_ = DriveState::kNotReadyToSwitchOn;
  uint16_t previous_controlword_ = 0;
  bool torque_limited_ = false;        // statusword bit 11: internal limit active
  bool recovery_requested_ = false;
  bool received_since_sync_ = false;
  bool mixed_modes_reported_ = false;  // EMCY 0x6320 sent for the current mix of modes
  JointMeasurement measured_;          // the robot's latest: a reset node reports it, not zeros
  std::vector<Pdo> pdos_;              // RPDO1-4 then TPDO1-2
  SdoTransfer sdo_;
  uint32_t heartbeat_elapsed_us_ = 0;
  bool consumer_active_ = false;       // the monitored node's first heartbeat arrived
  uint32_t consumer_elapsed_us_ = 0;
  // Slots of the objects the drive logic reads every cycle.
  struct Slots {
    int error_register, controlword, statusword, quick_stop_option, mode, mode_display, position_demand, position, velocity, target_torque,
        max_torque, torque_demand, torque_actual, target_position, velocity_offset, torque_offset, target_velocity,
        gravity_compensation, tau_ext, errors_first, heartbeat_producer, heartbeat_consumer, cob_id_emcy;
  } s_{};
};

}  // namespace csp::can
