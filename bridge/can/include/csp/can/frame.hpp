// Classic CAN frames (11-bit identifiers, up to 8 data bytes) and the CANopen (CiA 301)
// pre-defined connection set: COB-ID = function code + node id.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>

namespace csp::can {

struct Frame {
  uint32_t id = 0;    // 11-bit identifier (COB-ID)
  uint8_t dlc = 0;    // data length, 0..8
  std::array<uint8_t, 8> data{};

  bool operator==(const Frame&) const = default;
};

// CiA 301 pre-defined connection set (function codes; add the node id where one applies).
inline constexpr uint32_t kNmt = 0x000;
inline constexpr uint32_t kSync = 0x080;
inline constexpr uint32_t kEmcy = 0x080;
inline constexpr uint32_t kTpdo1 = 0x180, kRpdo1 = 0x200, kTpdo2 = 0x280, kRpdo2 = 0x300;
inline constexpr uint32_t kRpdo3 = 0x400, kRpdo4 = 0x500;   // (TPDO3/4, 0x380/0x480, are not used)
inline constexpr uint32_t kSdoTx = 0x580;   // server -> client
inline constexpr uint32_t kSdoRx = 0x600;   // client -> server
inline constexpr uint32_t kHeartbeat = 0x700;
// Bit 31 of a COB-ID object (0x1014, PDO communication sub-index 1): the EMCY or PDO does not exist.
inline constexpr uint32_t kCobIdInvalid = 0x80000000u;

// CiA 301 "restricted CAN-IDs" (7.3.5, the table of the pre-defined connection set): NMT 0x000,
// reserved 0x001-0x07F, 0x101-0x180, default SDO 0x581-0x5FF and 0x601-0x67F, reserved 0x6E0-0x6FF,
// NMT error control 0x701-0x77F, reserved 0x780-0x7FF. No configurable object (SYNC, TIME, EMCY,
// PDO, SDO) may use them.
inline bool is_restricted_can_id(uint32_t id) {
  return id <= 0x07F || (id >= 0x101 && id <= 0x180) || (id >= 0x581 && id <= 0x5FF) || (id >= 0x601 && id <= 0x67F) ||
         (id >= 0x6E0 && id <= 0x6FF) || id >= 0x701;
}

// A frame carrying `bytes` (at most 8).
inline Frame make_frame(uint32_t id, std::initializer_list<uint8_t> bytes) {
  Frame f;
  f.id = id;
  f.dlc = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  return f;
}

// A frame is well formed when its identifier has 11 bits and its length is 0..8.
bool is_valid(const Frame& frame);

// candump's compact form: "602#2B40600006000000" (hex id, '#', hex data bytes).
std::string to_string(const Frame& frame);
// The inverse of to_string; std::invalid_argument naming what is wrong.
Frame parse_frame(const std::string& text);
// "0x1A00": a value in hexadecimal as CiA 306 and messages write object indices and values,
// `digits` wide at least (0: as many as it takes).
std::string hex(uint64_t value, int digits);

// Little-endian field access (CANopen transmits least significant byte first).
inline uint64_t get_le(const uint8_t* bytes, int size) {
  uint64_t value = 0;
  for (int i = size - 1; i >= 0; --i) value = (value << 8) | bytes[i];
  return value;
}
inline void put_le(uint8_t* bytes, int size, uint64_t value) {
  for (int i = 0; i < size; ++i) bytes[i] = static_cast<uint8_t>(value >> (8 * i));
}

}  // namespace csp::can
