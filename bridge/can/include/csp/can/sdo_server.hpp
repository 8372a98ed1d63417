// The SDO server of a node (CiA 301 SDO protocol; CANopenNode's CO_SDOserver): expedited and
// segmented download and upload of its objects, requests on 0x600+id, answers on 0x580+id. Block
// transfers are not supported.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "csp/can/frame.hpp"
#include "csp/can/nmt_slave.hpp"
#include "csp/can/object_values.hpp"

namespace csp::can {

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

class SdoServer {
 public:
  // Downloaded values go through `writer`.
  SdoServer(uint8_t node_id, const ObjectValues& values, ObjectWriter& writer, const NmtSlave& nmt,
            std::vector<Frame>& out);

  void receive(const Frame& request);
  // A reset drops the transfer in progress.
  void reset() { transfer_ = {}; }

 private:
  struct Transfer {   // a segmented transfer in progress
    enum class Kind { kNone, kDownload, kUpload } kind = Kind::kNone;
    int slot = -1;
    bool toggle = false;
    std::vector<uint8_t> data;
    size_t offset = 0;
  };

  // The entry a download (`for_write`) or upload addresses, or -1 after the abort that says why not.
  int find_entry(uint16_t index, uint8_t subindex, bool for_write);
  // A segment (command byte `command`) continues the transfer in progress, of `kind`, with the
  // toggle bit expected; false after the abort that says why not.
  bool continues_transfer(Transfer::Kind kind, uint8_t command);
  // Checks the length, decodes and hands the value to the writer; 0 or the abort code.
  uint32_t write(int slot, const uint8_t* bytes, size_t size);
  void abort_transfer(uint16_t index, uint8_t subindex, uint32_t code);
  void send(const std::array<uint8_t, 8>& bytes);

  uint8_t node_id_;
  const ObjectValues& values_;
  ObjectWriter& writer_;
  const NmtSlave& nmt_;
  std::vector<Frame>& out_;
  Transfer transfer_;
};

}  // namespace csp::can
