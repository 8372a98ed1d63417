// A small CANopen master for seven CiA 402 joint drives with CSP's default PDO mapping (docs/can.md):
// NMT, expedited SDO, the 402 walk, and the cycle a controller runs: its targets in RPDOs, then
// SYNC, then the drives' TPDOs. It reads each drive's scaling (0x6076) by SDO, so it needs no
// knowledge of CSP beyond the mapping; it works unchanged on vcan0 or a physical can0.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "csp/can/socketcan.hpp"

namespace csp::can {

// One drive's values from the TPDOs of a SYNC, SI units.
struct DriveFeedback {
  uint16_t statusword = 0;
  int8_t mode = 0;                 // 0x6061
  double q = 0.0, dq = 0.0;        // [rad], [rad/s]
  double tau_J = 0.0;              // [N m], gravity included
  double tau_ext_hat_filtered = 0.0;
};

// One emergency message.
struct Emergency {
  uint8_t node = 0;
  uint16_t code = 0;
  uint8_t error_register = 0;
  uint8_t franka_error = 0xFF;     // CSP's byte 3: libfranka error index, 0xFF none
};

class Master {
 public:
  // The drives' node ids, joint 1..7 (CSP's default 1..7). `timeout_s`: SDO answers and TPDOs.
  explicit Master(const std::string& interface, std::array<uint8_t, 7> nodes = {1, 2, 3, 4, 5, 6, 7}, double timeout_s = 1.0);

  // NMT start of the seven nodes after reading their device type (0x1000 must be a 402 drive)
  // and rated torque (0x6076, the torque scaling). std::runtime_error naming the node on failure.
  void start();
  // Expedited SDO; std::runtime_error with the abort code on an abort or no answer.
  uint32_t sdo_read(int joint, uint16_t index, uint8_t subindex);
  void sdo_write(int joint, uint16_t index, uint8_t subindex, uint32_t value, int bytes);

  // Modes of operation (0x6060 by SDO): 8 CSP, 9 CSV, 10 CST.
  void set_mode(int8_t mode);
  // One cycle: controlword and targets to every drive (RPDO1: controlword + torque; CSP adds
  // RPDO2 position, CSV RPDO3 velocity), SYNC, and the 14 TPDOs it triggers.
  // std::runtime_error if a drive's TPDOs do not come within the timeout.
  const std::array<DriveFeedback, 7>& cycle(uint16_t controlword, const std::array<double, 7>& targets);
  // Shutdown, switch on, enable operation (a fault reset first if a drive is in fault), holding
  // `targets` meanwhile; the cycles it takes; std::runtime_error if a drive does not follow.
  int enable(const std::array<double, 7>& targets);

  const std::array<DriveFeedback, 7>& feedback() const { return feedback_; }
  // Every EMCY seen since the last clear.
  const std::vector<Emergency>& emergencies() const { return emergencies_; }
  void clear_emergencies() { emergencies_.clear(); }
  int8_t mode() const { return mode_; }

 private:
  void send(uint32_t id, std::initializer_list<uint8_t> bytes);
  void send(const Frame& frame);
  // Waits for a frame with `id`, handling every other frame on the way; false on timeout.
  bool wait_for(uint32_t id, Frame& out);
  void handle(const Frame& frame);

  SocketCan socket_;
  std::array<uint8_t, 7> nodes_;
  int64_t timeout_ns_;
  std::array<double, 7> torque_step_{};   // [N m] per per-mille step (0x6076 mN m / 1000 / 1000)
  std::array<DriveFeedback, 7> feedback_{};
  std::array<uint8_t, 7> tpdos_seen_{};   // bit 0 TPDO1, bit 1 TPDO2 in this cycle
  std::vector<Emergency> emergencies_;
  int8_t mode_ = 10;
};

}  // namespace csp::can
