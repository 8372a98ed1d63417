// The load frames would put on a real CAN bus of a given bitrate (vcan has none): classic frames
// with 11-bit identifiers, their length with worst-case bit stuffing, as can-utils' canbusload
// counts them by default: 47 + 8 n bits plus floor((34 + 8 n - 1) / 4) stuff bits for n data
// bytes (SOF .. EOF and the 3-bit interframe space; 55 / 95 / 135 bits for 0 / 4 / 8 bytes).
#pragma once

#include <cstdint>

#include "csp/can/frame.hpp"

namespace csp::can {

// Bits one classic 11-bit frame of `data_bytes` (0..8) occupies, worst-case stuffing included.
constexpr uint32_t frame_bits(uint32_t data_bytes) { return 47 + 8 * data_bytes + (34 + 8 * data_bytes - 1) / 4; }

class BusLoad {
 public:
  void add(const Frame& frame) {
    ++frames_;
    bits_ += frame_bits(frame.dlc);
  }
  uint64_t frames() const { return frames_; }
  uint64_t bits() const { return bits_; }

 private:
  uint64_t frames_ = 0, bits_ = 0;
};

}  // namespace csp::can
