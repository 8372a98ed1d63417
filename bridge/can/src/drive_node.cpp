#include "csp/can/drive_node.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace csp::can {

const char* nmt_state_name(NmtState state) {
  switch (state) {
    case NmtState::kInitialising: return "initialising";
    case NmtState::kStopped: return "stopped";
    case NmtState::kOperational: return "operational";
    case NmtState::kPreOperational: return "pre-operational";
  }
  return "?";
}

namespace {

constexpr uint32_t kPdoInvalid = 0x80000000u;   // COB-ID bit 31: the PDO does not exist

int64_t decode(DataType type, const uint8_t* bytes, int size) {
  const uint64_t raw = get_le(bytes, size);
  if (!is_signed(type) || size == 8) return static_cast<int64_t>(raw);
  const uint64_t sign = uint64_t{1} << (8 * size - 1);
  return static_cast<int64_t>((raw ^ sign) - sign);   // sign extension
}

// SI value -> raw integer of `type`, rounded and saturated to the type's range.
int64_t to_raw(double value, double step, int64_t low, int64_t high) {
  if (!std::isfinite(value)) return 0;
  const double raw = std::round(value / step);
  return static_cast<int64_t>(std::clamp(raw, static_cast<double>(low), static_cast<double>(high)));
}

}  // namespace

DriveNode::DriveNode(uint8_t node_id, const JointDrive& drive, const Identity& identity, std::vector<Frame>& out)
    : node_id_(node_id), drive_(drive), table_(object_table(drive, identity)), out_(out) {
  if (node_id < 1 || node_id > 127) throw std::invalid_argument("CANopen node id must be 1..127, got " + std::to_string(node_id));
  s_.error_register = slot(od::kErrorRegister, 0);
  s_.controlword = slot(od::kControlword, 0);
  s_.statusword = slot(od::kStatusword, 0);
  s_.quick_stop_option = slot(od::kQuickStopOptionCode, 0);
  s_.mode = slot(od::kModesOfOperation, 0);
  s_.mode_display = slot(od::kModesOfOperationDisplay, 0);
  s_.position_demand = slot(od::kPositionDemandValue, 0);
  s_.position = slot(od::kPositionActualValue, 0);
  s_.velocity = slot(od::kVelocityActualValue, 0);
  s_.target_torque = slot(od::kTargetTorque, 0);
  s_.max_torque = slot(od::kMaxTorque, 0);
  s_.torque_demand = slot(od::kTorqueDemand, 0);
  s_.torque_actual = slot(od::kTorqueActualValue, 0);
  s_.target_position = slot(od::kTargetPosition, 0);
  s_.velocity_offset = slot(od::kVelocityOffset, 0);
  s_.torque_offset = slot(od::kTorqueOffset, 0);
  s_.target_velocity = slot(od::kTargetVelocity, 0);
  s_.gravity_compensation = slot(od::kGravityCompensation, 0);
  s_.tau_ext = slot(od::kTauExtHatFiltered, 0);
  s_.errors_first = slot(od::kCurrentErrors, 1);
  s_.heartbeat_producer = slot(od::kProducerHeartbeatTime, 0);
  s_.heartbeat_consumer = slot(od::kConsumerHeartbeatTime, 1);
  s_.cob_id_emcy = slot(od::kCobIdEmcy, 0);
  for (int i = 0; i < od::kNumRpdos; ++i) pdos_.push_back({od::kRpdoCommunication + i, true, {}});
  for (int i = 0; i < od::kNumTpdos; ++i) pdos_.push_back({od::kTpdoCommunication + i, false, {}});
  values_.resize(table_.entries.size());
  reset(false);
}

int DriveNode::slot(uint16_t index, uint8_t subindex) const {
  const int s = table_.find(index, subindex);
  if (s < 0) throw std::logic_error("object table lacks an object the drive uses");
  return s;
}

int64_t DriveNode::value(uint16_t index, uint8_t subindex) const { return values_[slot(index, subindex)]; }

// NMT reset node (all objects) or reset communication (0x1000-0x1FFF), then boot-up.
void DriveNode::reset(bool communication_only) {
  for (size_t i = 0; i < table_.entries.size(); ++i) {
    const Entry& e = table_.entries[i];
    if (communication_only && e.index >= 0x2000) continue;
    values_[i] = e.default_value + (e.plus_node_id ? node_id_ : 0);
  }
  write_measurement();
  rebuild_pdos();
  sdo_ = {};
  heartbeat_elapsed_us_ = 0;
  consumer_active_ = false;
  consumer_elapsed_us_ = 0;
  if (!communication_only) {
    previous_controlword_ = 0;
    torque_limited_ = false;
    recovery_requested_ = false;
    received_since_sync_ = false;
    mixed_modes_reported_ = false;
    set_state(next_state(DriveState::kNotReadyToSwitchOn, 0, 0, 0));   // self-test done: switch on disabled
  }
  boot_up();
}

void DriveNode::boot_up() {
  nmt_ = NmtState::kInitialising;
  send(kHeartbeat + node_id_, {0x00});   // boot-up message
  nmt_ = NmtState::kPreOperational;
}

void DriveNode::nmt_command(uint8_t command) {
  switch (command) {
    case kNmtStart: nmt_ = NmtState::kOperational; break;
    case kNmtStop: nmt_ = NmtState::kStopped; break;
    case kNmtEnterPreOperational: nmt_ = NmtState::kPreOperational; break;
    case kNmtResetNode: reset(false); break;
    case kNmtResetCommunication: reset(true); break;
    default: break;   // unknown command specifiers are ignored (CiA 301)
  }
}

// ---------------------------------------------------------------- SDO server
void DriveNode::send_sdo(const std::array<uint8_t, 8>& bytes) {
  Frame f;
  f.id = kSdoTx + node_id_;
  f.dlc = 8;
  f.data = bytes;
  out_.push_back(f);
}

void DriveNode::sdo_abort(uint16_t index, uint8_t subindex, uint32_t code) {
  std::array<uint8_t, 8> b{0x80, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), subindex};
  put_le(&b[4], 4, code);
  send_sdo(b);
  sdo_ = {};
}

std::vector<uint8_t> DriveNode::read_bytes(int s) const {
  const Entry& e = table_.entries[s];
  if (e.type == DataType::kVisibleString) return {e.text.begin(), e.text.end()};
  std::vector<uint8_t> bytes(size_of(e.type));
  put_le(bytes.data(), size_of(e.type), static_cast<uint64_t>(values_[s]));
  return bytes;
}

void DriveNode::receive_sdo(const Frame& request) {
  if (nmt_ == NmtState::kStopped || request.dlc != 8) return;   // CiA 301: SDO needs all 8 bytes
  const uint8_t* d = request.data.data();
  const int command = d[0] >> 5;
  const uint16_t index = static_cast<uint16_t>(d[1] | (d[2] << 8));
  const uint8_t subindex = d[3];
  auto find_entry = [&](bool for_write) -> int {
    if (table_.object(index) == nullptr) return sdo_abort(index, subindex, abort::kNoObject), -1;
    const int s = table_.find(index, subindex);
    if (s < 0) return sdo_abort(index, subindex, abort::kNoSubindex), -1;
    const Access a = table_.entries[s].access;
    if (for_write && !writable(a)) return sdo_abort(index, subindex, abort::kReadOnly), -1;
    if (!for_write && !readable(a)) return sdo_abort(index, subindex, abort::kWriteOnly), -1;
    return s;
  };
  switch (command) {
    case 1: {   // initiate download: e = bit 1, s = bit 0, n = bits 2-3
      const int s = find_entry(true);
      if (s < 0) return;
      const bool expedited = d[0] & 0x02, size_indicated = d[0] & 0x01;
      if (expedited) {
        const int type_size = std::max(size_of(table_.entries[s].type), 1);
        const size_t size = size_indicated ? 4 - ((d[0] >> 2) & 0x3) : static_cast<size_t>(type_size);
        const uint32_t code = sdo_write(s, d + 4, size);
        if (code != 0) return sdo_abort(index, subindex, code);
        send_sdo({0x60, d[1], d[2], subindex, 0, 0, 0, 0});
        return;
      }
      sdo_ = {SdoTransfer::Kind::kDownload, s, false, {}, 0};
      send_sdo({0x60, d[1], d[2], subindex, 0, 0, 0, 0});
      return;
    }
    case 0: {   // download segment: t = bit 4, n = bits 1-3, c = bit 0
      if (sdo_.kind != SdoTransfer::Kind::kDownload) return sdo_abort(0, 0, abort::kUnknownCommand);
      const Entry& e = table_.entries[sdo_.slot];
      const bool toggle = d[0] & 0x10;
      if (toggle != sdo_.toggle) return sdo_abort(e.index, e.subindex, abort::kToggleBit);
      const int n = 7 - ((d[0] >> 1) & 0x7);
      if (sdo_.data.size() + n > 8) return sdo_abort(e.index, e.subindex, abort::kLengthTooHigh);
      sdo_.data.insert(sdo_.data.end(), d + 1, d + 1 + n);
      if (d[0] & 0x01) {   // last segment: the value is written (or refused) before the answer
        const uint32_t code = sdo_write(sdo_.slot, sdo_.data.data(), sdo_.data.size());
        if (code != 0) return sdo_abort(e.index, e.subindex, code);
        sdo_ = {};
      } else {
        sdo_.toggle = !sdo_.toggle;
      }
      send_sdo({static_cast<uint8_t>(0x20 | (toggle ? 0x10 : 0)), 0, 0, 0, 0, 0, 0, 0});
      return;
    }
    case 2: {   // initiate upload
      const int s = find_entry(false);
      if (s < 0) return;
      std::vector<uint8_t> bytes = read_bytes(s);
      if (bytes.size() <= 4) {   // expedited: 0x4F / 0x4B / 0x47 / 0x43 for 1..4 bytes
        std::array<uint8_t, 8> b{static_cast<uint8_t>(0x43 | ((4 - bytes.size()) << 2)), d[1], d[2], subindex};
        std::copy(bytes.begin(), bytes.end(), b.begin() + 4);
        send_sdo(b);
        return;
      }
      std::array<uint8_t, 8> b{0x41, d[1], d[2], subindex};   // segmented, size indicated
      put_le(&b[4], 4, bytes.size());
      send_sdo(b);
      sdo_ = {SdoTransfer::Kind::kUpload, s, false, std::move(bytes), 0};
      return;
    }
    case 3: {   // upload segment
      if (sdo_.kind != SdoTransfer::Kind::kUpload) return sdo_abort(0, 0, abort::kUnknownCommand);
      const Entry& e = table_.entries[sdo_.slot];
      const bool toggle = d[0] & 0x10;
      if (toggle != sdo_.toggle) return sdo_abort(e.index, e.subindex, abort::kToggleBit);
      const size_t n = std::min<size_t>(7, sdo_.data.size() - sdo_.offset);
      const bool last = sdo_.offset + n == sdo_.data.size();
      std::array<uint8_t, 8> b{static_cast<uint8_t>((toggle ? 0x10 : 0) | ((7 - n) << 1) | (last ? 1 : 0))};
      std::copy_n(sdo_.data.begin() + static_cast<long>(sdo_.offset), n, b.begin() + 1);
      send_sdo(b);
      sdo_.offset += n;
      sdo_.toggle = !sdo_.toggle;
      if (last) sdo_ = {};
      return;
    }
    case 4: sdo_ = {}; return;   // the client aborts: no answer
    default: sdo_abort(index, subindex, abort::kUnknownCommand); return;   // block transfers are not supported
  }
}

uint32_t DriveNode::sdo_write(int s, const uint8_t* bytes, size_t size) {
  const Entry& e = table_.entries[s];
  const size_t type_size = static_cast<size_t>(size_of(e.type));
  if (size > type_size) return abort::kLengthTooHigh;
  if (size < type_size) return abort::kLengthTooLow;
  const int64_t value = decode(e.type, bytes, static_cast<int>(size));
  if (value < e.low) return abort::kValueTooLow;
  if (value > e.high) return abort::kValueTooHigh;
  if (const uint32_t code = check_pdo_parameter(s, value); code != 0) return code;
  store(s, value);
  return 0;
}

// ---------------------------------------------------------------- PDOs
uint32_t DriveNode::cob_id(const Pdo& pdo) const {
  return static_cast<uint32_t>(values_[table_.find(static_cast<uint16_t>(pdo.communication_index), 1)]);
}
bool DriveNode::pdo_valid(const Pdo& pdo) const { return (cob_id(pdo) & kPdoInvalid) == 0; }

// The mapping's first `count` entries as slots; 0 or the abort code.
uint32_t DriveNode::build_map(Pdo& pdo, int count, std::vector<MappedValue>* map) const {
  const uint16_t map_index = static_cast<uint16_t>(pdo.communication_index + 0x200);
  const int first = table_.find(map_index, 1);
  int bits = 0;
  for (int i = 0; i < count; ++i) {
    const uint32_t m = static_cast<uint32_t>(values_[first + i]);
    const int s = table_.find(static_cast<uint16_t>(m >> 16), static_cast<uint8_t>(m >> 8));
    if (s < 0 || !table_.entries[s].pdo_mappable) return abort::kNotMappable;
    const Entry& e = table_.entries[s];
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
uint32_t DriveNode::check_pdo_parameter(int s, int64_t value) const {
  const Entry& e = table_.entries[s];
  const bool communication = (e.index & 0xFE00) == 0x1400 || (e.index & 0xFE00) == 0x1800;
  const bool mapping = (e.index & 0xFE00) == 0x1600 || (e.index & 0xFE00) == 0x1A00;
  if (!communication && !mapping) return 0;
  const uint16_t communication_index = communication ? e.index : static_cast<uint16_t>(e.index - 0x200);
  const auto it = std::find_if(pdos_.begin(), pdos_.end(),
                               [&](const Pdo& p) { return p.communication_index == communication_index; });
  const Pdo& pdo = *it;
  if (communication && e.subindex == 1) {
    const uint32_t id = static_cast<uint32_t>(value);
    if ((id & kPdoInvalid) == 0 && (id & 0x3FFFF800u) != 0) return abort::kInvalidValue;   // 11-bit ids only
    if (pdo_valid(pdo) && (id & kPdoInvalid) == 0 && id != cob_id(pdo)) return abort::kInvalidValue;
    return 0;
  }
  if (communication && e.subindex == 2) {
    const bool synchronous = pdo.receive ? value <= 240 : value >= 1 && value <= 240;
    return synchronous || (pdo.receive && value >= 254) ? 0 : abort::kInvalidValue;
  }
  if (pdo_valid(pdo)) return abort::kDeviceState;
  const int count_slot = table_.find(e.index, 0);
  if (e.subindex == 0) {
    Pdo copy = pdo;
    return build_map(copy, static_cast<int>(value), nullptr);
  }
  if (values_[count_slot] != 0) return abort::kDeviceState;
  if (value == 0) return 0;   // clearing an entry
  const int target = table_.find(static_cast<uint16_t>(value >> 16), static_cast<uint8_t>(value >> 8));
  if (target < 0) return abort::kNotMappable;
  return table_.entries[target].pdo_mappable ? 0 : abort::kNotMappable;
}

void DriveNode::rebuild_pdos() {
  for (Pdo& pdo : pdos_) {
    pdo.map.clear();
    const int count = static_cast<int>(values_[table_.find(static_cast<uint16_t>(pdo.communication_index + 0x200), 0)]);
    build_map(pdo, count, &pdo.map);   // defaults and checked writes always build
    pdo.bytes = 0;
    for (const MappedValue& m : pdo.map) pdo.bytes += m.bytes;
    pdo.pending = false;
    pdo.sync_count = 0;
  }
}

bool DriveNode::receive_rpdo(const Frame& frame) {
  for (Pdo& pdo : pdos_) {
    if (!pdo.receive || !pdo_valid(pdo) || (cob_id(pdo) & 0x7FF) != frame.id) continue;
    if (nmt_ != NmtState::kOperational) return true;   // PDOs only in operational
    if (frame.dlc < pdo.bytes) {                       // CiA 301: not processed, EMCY
      send_emcy(kEmcyPdoLength, -1);
      return true;
    }
    if (frame.dlc > pdo.bytes) send_emcy(kEmcyPdoLengthExceeded, -1);   // the first bytes are used
    const int transmission = static_cast<int>(values_[table_.find(static_cast<uint16_t>(pdo.communication_index), 2)]);
    if (transmission <= 240) {   // synchronous: takes effect at the next SYNC
      pdo.data = frame.data;
      pdo.pending = true;
    } else {
      apply_rpdo(pdo, frame.data.data());
    }
    return true;
  }
  return false;
}

void DriveNode::apply_rpdo(const Pdo& pdo, const uint8_t* data) {
  int offset = 0;
  for (const MappedValue& m : pdo.map) {
    const Entry& e = table_.entries[m.slot];
    const int64_t value = decode(e.type, data + offset, m.bytes);
    offset += m.bytes;
    if (value < e.low || value > e.high) continue;   // out of range (e.g. mode 3): not applied
    store(m.slot, value);
  }
}

void DriveNode::sync_transmit() {
  if (nmt_ != NmtState::kOperational) return;
  for (Pdo& pdo : pdos_) {
    if (pdo.receive || !pdo_valid(pdo)) continue;
    const int transmission = static_cast<int>(values_[table_.find(static_cast<uint16_t>(pdo.communication_index), 2)]);
    if (++pdo.sync_count < static_cast<uint32_t>(transmission)) continue;   // every n-th SYNC
    pdo.sync_count = 0;
    Frame f;
    f.id = cob_id(pdo) & 0x7FF;
    f.dlc = static_cast<uint8_t>(pdo.bytes);
    int offset = 0;
    for (const MappedValue& m : pdo.map) {   // little-endian; build_map keeps a PDO within 8 bytes
      const auto value = static_cast<uint64_t>(values_[m.slot]);
      for (int b = 0; b < m.bytes && offset < 8; ++b) f.data[offset++] = static_cast<uint8_t>(value >> (8 * b));
    }
    out_.push_back(f);
  }
}

void DriveNode::sync_latch() {
  received_since_sync_ = false;
  // A cycle after a fault or a quick stop, the robot's reaction is over (transitions 14 and 12).
  if (state_ == DriveState::kFaultReactionActive) set_state(DriveState::kFault);
  set_state(quick_stop_over(state_, static_cast<int>(values_[s_.quick_stop_option])));
  for (Pdo& pdo : pdos_) {
    if (!pdo.pending) continue;
    apply_rpdo(pdo, pdo.data.data());
    pdo.pending = false;
    received_since_sync_ = true;
  }
}

void DriveNode::receive_sync(const Frame& frame) {
  if (frame.dlc > 1) send_emcy(kEmcySyncLength, -1);   // SYNC carries no data or the 1-byte counter
}

// ---------------------------------------------------------------- CiA 402
void DriveNode::set_controlword(uint16_t controlword) {
  const DriveState before = state_;
  set_state(next_state(state_, controlword, previous_controlword_, static_cast<int>(values_[s_.quick_stop_option])));
  previous_controlword_ = controlword;
  if (before == DriveState::kFault && state_ == DriveState::kSwitchOnDisabled) {   // fault reset
    recovery_requested_ = true;
    values_[s_.error_register] = 0;
    send_emcy(kEmcyErrorReset, -1);
  }
}

void DriveNode::set_state(DriveState state) {
  state_ = state;
  const bool following = state == DriveState::kOperationEnabled;
  values_[s_.statusword] = statusword_state_bits(state) | 0x0200   // bit 9 remote: the controlword is obeyed
                           | (torque_limited_ ? 0x0800 : 0)          // bit 11 internal limit active
                           | (following ? 0x1000 : 0);               // bit 12: the drive follows the target
}

bool DriveNode::take_recovery_request() {
  const bool requested = recovery_requested_;
  recovery_requested_ = false;
  return requested;
}

JointCommand DriveNode::command() const {
  const double torque_step = drive_.rated_torque_mNm * 1e-6;   // [N m] per per-mille step
  JointCommand c;
  c.mode = static_cast<int8_t>(values_[s_.mode_display]);
  c.operation_enabled = state_ == DriveState::kOperationEnabled;
  c.received = received_since_sync_;
  c.target_position = static_cast<double>(values_[s_.target_position]) * 1e-6;
  c.target_velocity = static_cast<double>(values_[s_.target_velocity] + values_[s_.velocity_offset]) * 1e-6;
  const int64_t limit = values_[s_.max_torque];
  c.target_torque =
      static_cast<double>(std::clamp(values_[s_.target_torque] + values_[s_.torque_offset], -limit, limit)) * torque_step;
  c.gravity_compensation = values_[s_.gravity_compensation] != 0;
  return c;
}

void DriveNode::write_measurement() {
  const double torque_step = drive_.rated_torque_mNm * 1e-6;
  const JointMeasurement& m = measured_;
  values_[s_.position_demand] = to_raw(m.q_d, 1e-6, INT32_MIN, INT32_MAX);
  values_[s_.position] = to_raw(m.q, 1e-6, INT32_MIN, INT32_MAX);
  values_[s_.velocity] = to_raw(m.dq, 1e-6, INT32_MIN, INT32_MAX);
  values_[s_.torque_actual] = to_raw(m.tau_J, torque_step, INT16_MIN, INT16_MAX);
  values_[s_.torque_demand] = to_raw(m.tau_J_d, torque_step, INT16_MIN, INT16_MAX);
  values_[s_.tau_ext] = to_raw(m.tau_ext_hat_filtered, torque_step, INT16_MIN, INT16_MAX);
}

void DriveNode::update(const JointMeasurement& m, const rt::ErrorSet& errors, bool mixed_modes) {
  measured_ = m;
  write_measurement();
  const bool in_mix = mixed_modes && state_ == DriveState::kOperationEnabled;
  if (in_mix && !mixed_modes_reported_) send_emcy(kEmcyMixedModes, -1);   // once per mix; the error register is unchanged
  mixed_modes_reported_ = in_mix;
  const int64_t limit = values_[s_.max_torque];
  torque_limited_ = std::llabs(values_[s_.target_torque] + values_[s_.torque_offset]) > limit &&
                    state_ == DriveState::kOperationEnabled && values_[s_.mode_display] == kModeCst;
  for (int i = 0; i < rt::kNumErrors; ++i) values_[s_.errors_first + i] = errors.flags()[i] ? 1 : 0;
  if (errors && state_ != DriveState::kFault && state_ != DriveState::kFaultReactionActive) {
    bool first = true;
    for (int i = 0; i < rt::kNumErrors; ++i) {
      if (!errors.flags()[i]) continue;
      const bool communication = i == static_cast<int>(rt::Error::communication_constraints_violation);
      const uint8_t register_bits = 0x01 | (communication ? 0x10 : 0x80);   // generic + communication / manufacturer
      if (first) enter_fault(emcy_code_of_error(i), i, register_bits);
      else send_emcy(emcy_code_of_error(i), i);
      first = false;
    }
  }
  set_state(state_);   // refresh the statusword's bits
}

void DriveNode::enter_fault(uint16_t emcy_code, int error, uint8_t register_bits) {
  set_state(fault(state_));
  values_[s_.error_register] |= register_bits;
  send_emcy(emcy_code, error);
}

// ---------------------------------------------------------------- EMCY, heartbeat
void DriveNode::send_emcy(uint16_t code, int error) {
  const uint32_t id = static_cast<uint32_t>(values_[s_.cob_id_emcy]);
  if ((id & kPdoInvalid) || nmt_ == NmtState::kStopped) return;
  // code, error register, then CSP's manufacturer bytes: libfranka error index (0xFF: none), joint.
  send(id & 0x7FF, {static_cast<uint8_t>(code), static_cast<uint8_t>(code >> 8), static_cast<uint8_t>(values_[s_.error_register]),
                    static_cast<uint8_t>(error < 0 ? 0xFF : error), static_cast<uint8_t>(drive_.joint), 0, 0, 0});
}

void DriveNode::receive_heartbeat(uint8_t producer, uint8_t /*state*/) {
  const uint32_t consumer = static_cast<uint32_t>(values_[s_.heartbeat_consumer]);
  if (((consumer >> 16) & 0x7F) != producer || (consumer & 0xFFFF) == 0) return;
  consumer_active_ = true;
  consumer_elapsed_us_ = 0;
}

void DriveNode::elapse(uint32_t microseconds) {
  const uint32_t producer_us = static_cast<uint32_t>(values_[s_.heartbeat_producer]) * 1000;
  if (producer_us > 0) {
    heartbeat_elapsed_us_ += microseconds;
    while (heartbeat_elapsed_us_ >= producer_us) {
      heartbeat_elapsed_us_ -= producer_us;
      send(kHeartbeat + node_id_, {static_cast<uint8_t>(nmt_)});
    }
  }
  const uint32_t consumer = static_cast<uint32_t>(values_[s_.heartbeat_consumer]);
  const uint32_t consumer_us = (consumer & 0xFFFF) * 1000;
  if (consumer_active_ && consumer_us > 0) {
    consumer_elapsed_us_ += microseconds;
    if (consumer_elapsed_us_ > consumer_us) {   // the master went silent: fault, like a lost FCI connection
      consumer_active_ = false;
      enter_fault(kEmcyHeartbeat, -1, 0x11);
    }
  }
}

void DriveNode::store(int s, int64_t value) {
  values_[s] = value;
  const Entry& e = table_.entries[s];
  if (s == s_.controlword) set_controlword(static_cast<uint16_t>(value));
  else if (s == s_.mode) values_[s_.mode_display] = value;   // the mode changes at once
  else if (e.index == od::kAutomaticErrorRecovery) recovery_requested_ = true;
  else if (s == s_.heartbeat_producer) heartbeat_elapsed_us_ = 0;
  else if (s == s_.heartbeat_consumer) consumer_active_ = false;
  else if ((e.index & 0xFE00) == 0x1600 || (e.index & 0xFE00) == 0x1A00 || (e.index & 0xFE00) == 0x1400 ||
           (e.index & 0xFE00) == 0x1800)
    rebuild_pdos();
}

void DriveNode::send(uint32_t id, std::initializer_list<uint8_t> bytes) {
  Frame f;
  f.id = id;
  f.dlc = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  out_.push_back(f);
}

}  // namespace csp::can
