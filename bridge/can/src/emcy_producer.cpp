#include "csp/can/emcy_producer.hpp"

namespace csp::can {

EmcyProducer::EmcyProducer(int joint, ObjectValues& values, const NmtSlave& nmt, std::vector<Frame>& out)
    : joint_(joint),
      values_(values),
      nmt_(nmt),
      out_(out),
      error_register_slot_(values.slot(od::kErrorRegister, 0)),
      cob_id_slot_(values.slot(od::kCobIdEmcy, 0)) {}

void EmcyProducer::send(uint16_t code, int franka_error, uint8_t register_bits) {
  values_[error_register_slot_] |= register_bits;
  const uint32_t id = static_cast<uint32_t>(values_[cob_id_slot_]);
  if ((id & kCobIdInvalid) || nmt_.state() == NmtState::kStopped) return;
  // code, error register, then CSP's manufacturer bytes: libfranka error index (0xFF: none), joint.
  out_.push_back(make_frame(id & 0x7FF, {static_cast<uint8_t>(code), static_cast<uint8_t>(code >> 8),
                                         static_cast<uint8_t>(values_[error_register_slot_]),
                                         static_cast<uint8_t>(franka_error < 0 ? 0xFF : franka_error),
                                         static_cast<uint8_t>(joint_), 0, 0, 0}));
}

void EmcyProducer::reset_errors() {
  values_[error_register_slot_] = 0;
  send(kEmcyErrorReset);
}

}  // namespace csp::can
