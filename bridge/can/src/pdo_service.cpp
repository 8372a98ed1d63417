#include "csp/can/pdo_service.hpp"

#include <algorithm>

#include "csp/can/sdo_server.hpp"

namespace csp::can {

namespace {
bool is_communication_parameter(uint16_t index) { return (index & 0xFE00) == 0x1400 || (index & 0xFE00) == 0x1800; }
bool is_mapping_parameter(uint16_t index) { return (index & 0xFE00) == 0x1600 || (index & 0xFE00) == 0x1A00; }
}  // namespace

uint32_t check_cob_id(uint32_t current, uint32_t value, uint32_t sync_cob_id) {
  const bool on = (value & kCobIdInvalid) == 0;
  if (!on) return 0;   // switching off (or staying off) is always allowed
  const uint32_t id = value & 0x7FF;
  if ((value & 0x3FFFF800u) != 0) return abort::kInvalidValue;                        // 11-bit ids only
  if ((current & kCobIdInvalid) == 0 && value != current) return abort::kInvalidValue;  // moved while valid
  if (is_restricted_can_id(id) || id == (sync_cob_id & 0x7FF)) return abort::kInvalidValue;
  return 0;
}

PdoService::PdoService(const ObjectValues& values, ObjectWriter& writer, const NmtSlave& nmt, EmcyProducer& emcy,
                       std::vector<Frame>& out)
    : values_(values), writer_(writer), nmt_(nmt), emcy_(emcy), out_(out) {
  for (int i = 0; i < od::kNumRpdos; ++i) pdos_.push_back({od::kRpdoCommunication + i, true, {}});
  for (int i = 0; i < od::kNumTpdos; ++i) pdos_.push_back({od::kTpdoCommunication + i, false, {}});
}

bool PdoService::is_parameter(uint16_t index) { return is_communication_parameter(index) || is_mapping_parameter(index); }

uint32_t PdoService::cob_id(const Pdo& pdo) const {
  return static_cast<uint32_t>(values_[values_.table().find(static_cast<uint16_t>(pdo.communication_index), 1)]);
}
bool PdoService::valid(const Pdo& pdo) const { return (cob_id(pdo) & kCobIdInvalid) == 0; }
int PdoService::transmission_type(const Pdo& pdo) const {
  return static_cast<int>(values_[values_.table().find(static_cast<uint16_t>(pdo.communication_index), 2)]);
}

// The mapping's first `count` entries as slots; 0 or the abort code.
uint32_t PdoService::build_map(const Pdo& pdo, int count, std::vector<MappedValue>* map) const {
  const ObjectTable& table = values_.table();
  const int first = table.find(static_cast<uint16_t>(pdo.communication_index + 0x200), 1);
  int bits = 0;
  for (int i = 0; i < count; ++i) {
    const uint32_t m = static_cast<uint32_t>(values_[first + i]);
    const int s = table.find(static_cast<uint16_t>(m >> 16), static_cast<uint8_t>(m >> 8));
    if (s < 0 || !table.entries[s].pdo_mappable) return abort::kNotMappable;
    const Entry& e = table.entries[s];
    if (pdo.receive ? !writable(e.access) : !readable(e.access)) return abort::kNotMappable;
    if ((m & 0xFF) != static_cast<uint32_t>(8 * size_of(e.type))) return abort::kIncompatible;   // byte granularity
    bits += static_cast<int>(m & 0xFF);
    if (bits > 64) return abort::kPdoLength;
    if (map) map->push_back({s, size_of(e.type)});
  }
  return 0;
}

// CiA 301 rules for changing a PDO: COB-ID only while invalid (bit 31), mapping only while the PDO
// is invalid and sub-index 0 is 0; sub-index 0 = n checks the n entries.
uint32_t PdoService::check_parameter(int slot, int64_t value) const {
  const Entry& e = values_.entry(slot);
  const bool communication = is_communication_parameter(e.index);
  if (!communication && !is_mapping_parameter(e.index)) return 0;
  const uint16_t communication_index = communication ? e.index : static_cast<uint16_t>(e.index - 0x200);
  const Pdo& pdo = *std::find_if(pdos_.begin(), pdos_.end(),
                                 [&](const Pdo& p) { return p.communication_index == communication_index; });
  if (communication && e.subindex == 1)
    return check_cob_id(cob_id(pdo), static_cast<uint32_t>(value),
                        static_cast<uint32_t>(values_[values_.slot(od::kCobIdSync, 0)]));
  if (communication && e.subindex == 2) {
    const bool synchronous = pdo.receive ? value <= 240 : value >= 1 && value <= 240;
    return synchronous || (pdo.receive && value >= 254) ? 0 : abort::kInvalidValue;
  }
  if (valid(pdo)) return abort::kDeviceState;
  if (e.subindex == 0) return build_map(pdo, static_cast<int>(value), nullptr);
  if (values_[values_.slot(e.index, 0)] != 0) return abort::kDeviceState;
  if (value == 0) return 0;   // clearing an entry
  const int target = values_.table().find(static_cast<uint16_t>(value >> 16), static_cast<uint8_t>(value >> 8));
  if (target < 0) return abort::kNotMappable;
  return values_.entry(target).pdo_mappable ? 0 : abort::kNotMappable;
}

void PdoService::rebuild() {
  for (Pdo& pdo : pdos_) {
    pdo.map.clear();
    const int count = static_cast<int>(values_[values_.slot(static_cast<uint16_t>(pdo.communication_index + 0x200), 0)]);
    build_map(pdo, count, &pdo.map);   // defaults and checked writes always build
    pdo.bytes = 0;
    for (const MappedValue& m : pdo.map) pdo.bytes += m.bytes;
    pdo.pending = false;
    pdo.sync_count = 0;
  }
}

bool PdoService::receive(const Frame& frame) {
  for (Pdo& pdo : pdos_) {
    if (!pdo.receive || !valid(pdo) || (cob_id(pdo) & 0x7FF) != frame.id) continue;
    if (nmt_.state() != NmtState::kOperational) return true;   // PDOs only in operational
    if (frame.dlc < pdo.bytes) {                               // CiA 301: not processed, EMCY
      emcy_.send(kEmcyPdoLength);
      return true;
    }
    if (frame.dlc > pdo.bytes) emcy_.send(kEmcyPdoLengthExceeded);   // the first bytes are used
    if (transmission_type(pdo) <= 240) {   // synchronous: takes effect at the next SYNC
      pdo.data = frame.data;
      pdo.pending = true;
    } else {
      apply_rpdo(pdo, frame.data.data());
    }
    return true;
  }
  return false;
}

void PdoService::apply_rpdo(const Pdo& pdo, const uint8_t* data) {
  int offset = 0;
  for (const MappedValue& m : pdo.map) {
    const int64_t value = values_.decode(m.slot, data + offset, m.bytes);
    offset += m.bytes;
    writer_.write(m.slot, value);   // a value the node refuses (e.g. mode 3) is not applied
  }
}

void PdoService::transmit_sync() {
  if (nmt_.state() != NmtState::kOperational) return;
  for (Pdo& pdo : pdos_) {
    if (pdo.receive || !valid(pdo)) continue;
    if (++pdo.sync_count < static_cast<uint32_t>(transmission_type(pdo))) continue;   // every n-th SYNC
    pdo.sync_count = 0;
    Frame f;
    f.id = cob_id(pdo) & 0x7FF;
    f.dlc = static_cast<uint8_t>(pdo.bytes);
    int offset = 0;
    for (const MappedValue& m : pdo.map) {   // little-endian; build_map keeps a PDO within 8 bytes
      put_le(&f.data[offset], m.bytes, static_cast<uint64_t>(values_[m.slot]));
      offset += m.bytes;
    }
    out_.push_back(f);
  }
}

bool PdoService::latch_sync() {
  bool latched = false;
  for (Pdo& pdo : pdos_) {
    if (!pdo.pending) continue;
    apply_rpdo(pdo, pdo.data.data());
    pdo.pending = false;
    latched = true;
  }
  return latched;
}

}  // namespace csp::can
