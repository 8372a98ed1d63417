// The EMCY producer of a node (CiA 301 emergency object; CANopenNode's CO_Emergency): one frame
// per error event on the COB-ID of 0x1014, with the error register 0x1001, which it keeps.
#pragma once

#include <cstdint>
#include <vector>

#include "csp/can/frame.hpp"
#include "csp/can/nmt_slave.hpp"
#include "csp/can/object_values.hpp"

namespace csp::can {

// EMCY codes of the communication layer (CiA 301 / CiA 302 emergency error codes).
inline constexpr uint16_t kEmcyErrorReset = 0x0000, kEmcyHeartbeat = 0x8130, kEmcyPdoLength = 0x8210,
                          kEmcyPdoLengthExceeded = 0x8220, kEmcySyncLength = 0x8240, kEmcyRpdoTimeout = 0x8250;

class EmcyProducer {
 public:
  // `joint` goes into every message (CSP's manufacturer bytes).
  EmcyProducer(int joint, ObjectValues& values, const NmtSlave& nmt, std::vector<Frame>& out);

  // An error event: `register_bits` join the error register, then the EMCY reports `code` and
  // `franka_error`, libfranka's error index (-1: none). Not sent while 0x1014 is invalid
  // (bit 31) or the node is stopped.
  void send(uint16_t code, int franka_error = -1, uint8_t register_bits = 0);
  // The errors are gone (a fault reset): the register clears and EMCY 0x0000 says so.
  void reset_errors();

 private:
  int joint_;
  ObjectValues& values_;
  const NmtSlave& nmt_;
  std::vector<Frame>& out_;
  int error_register_slot_;   // 0x1001
  int cob_id_slot_;           // 0x1014
};

}  // namespace csp::can
