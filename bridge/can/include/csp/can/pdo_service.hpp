// The PDOs of a node (CiA 301 process data objects; CANopenNode's CO_PDO): RPDO1-4 and TPDO1-2
// as their communication (0x1400+i / 0x1800+i) and mapping (0x1600+i / 0x1A00+i) parameters say,
// remappable by SDO as a CiA 302 master does it. PDOs move only in operational.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "csp/can/emcy_producer.hpp"
#include "csp/can/frame.hpp"
#include "csp/can/nmt_slave.hpp"
#include "csp/can/object_values.hpp"

namespace csp::can {

// CiA 301 rules for writing a COB-ID object (PDO communication sub-index 1, EMCY 0x1014): 0, or the
// SDO abort code 0x06090030 (invalid value) that refuses changing `current` to `value`. An object
// that exists (bit 31 = 0) can only be switched off, not moved (set bit 31 first); 11-bit
// identifiers only; an object switched on may not use a restricted CAN-ID (is_restricted_can_id)
// nor the SYNC's (`sync_cob_id`, 0x1005), which would put its frames on the NMT, SYNC, SDO or
// heartbeat identifiers.
uint32_t check_cob_id(uint32_t current, uint32_t value, uint32_t sync_cob_id);

class PdoService {
 public:
  // RPDO values go through `writer`; length errors are reported through `emcy`.
  PdoService(const ObjectValues& values, ObjectWriter& writer, const NmtSlave& nmt, EmcyProducer& emcy,
             std::vector<Frame>& out);

  // A PDO communication or mapping parameter (0x1400-0x1BFF).
  static bool is_parameter(uint16_t index);
  // CiA 301 rules for changing a PDO: 0, or the SDO abort code that refuses `value` at `slot`.
  uint32_t check_parameter(int slot, int64_t value) const;
  // The parameters changed (or were reset): the mappings are read again, pending RPDOs dropped.
  void rebuild();

  // A frame on one of the RPDO COB-IDs; false if the COB-ID is not one of them.
  bool receive(const Frame& frame);
  // At a SYNC: the TPDOs due (every n-th SYNC for transmission type n) with the values as they are.
  void transmit_sync();
  // At a SYNC: the synchronous RPDOs received since the previous SYNC take effect; true if any.
  bool latch_sync();

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

  uint32_t cob_id(const Pdo& pdo) const;
  bool valid(const Pdo& pdo) const;
  int transmission_type(const Pdo& pdo) const;
  uint32_t build_map(const Pdo& pdo, int count, std::vector<MappedValue>* map) const;
  void apply_rpdo(const Pdo& pdo, const uint8_t* data);

  const ObjectValues& values_;
  ObjectWriter& writer_;
  const NmtSlave& nmt_;
  EmcyProducer& emcy_;
  std::vector<Frame>& out_;
  std::vector<Pdo> pdos_;   // RPDO1-4 then TPDO1-2
};

}  // namespace csp::can
