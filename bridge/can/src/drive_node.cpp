#include "csp/can/drive_node.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace csp::can {

namespace {

// SI value -> raw integer of `type`, rounded and saturated to the type's range.
int64_t to_raw(double value, double step, int64_t low, int64_t high) {
  if (!std::isfinite(value)) return 0;
  const double raw = std::round(value / step);
  return static_cast<int64_t>(std::clamp(raw, static_cast<double>(low), static_cast<double>(high)));
}

}  // namespace

DriveNode::DriveNode(uint8_t node_id, const JointDrive& drive, const Identity& identity, std::vector<Frame>& out)
    : node_id_(node_id),
      drive_(drive),
      values_(object_table(drive, identity), node_id),
      nmt_(node_id, values_, out),
      heartbeat_consumer_(values_),
      emcy_(drive.joint, values_, nmt_, out),
      pdos_(values_, *this, nmt_, emcy_, out),
      sdo_(node_id, values_, *this, nmt_, out) {
  if (node_id < 1 || node_id > 127) throw std::invalid_argument("CANopen node id must be 1..127, got " + std::to_string(node_id));
  s_.controlword = values_.slot(od::kControlword, 0);
  s_.statusword = values_.slot(od::kStatusword, 0);
  s_.quick_stop_option = values_.slot(od::kQuickStopOptionCode, 0);
  s_.mode = values_.slot(od::kModesOfOperation, 0);
  s_.mode_display = values_.slot(od::kModesOfOperationDisplay, 0);
  s_.position_demand = values_.slot(od::kPositionDemandValue, 0);
  s_.position = values_.slot(od::kPositionActualValue, 0);
  s_.velocity = values_.slot(od::kVelocityActualValue, 0);
  s_.target_torque = values_.slot(od::kTargetTorque, 0);
  s_.max_torque = values_.slot(od::kMaxTorque, 0);
  s_.torque_demand = values_.slot(od::kTorqueDemand, 0);
  s_.torque_actual = values_.slot(od::kTorqueActualValue, 0);
  s_.target_position = values_.slot(od::kTargetPosition, 0);
  s_.velocity_offset = values_.slot(od::kVelocityOffset, 0);
  s_.torque_offset = values_.slot(od::kTorqueOffset, 0);
  s_.target_velocity = values_.slot(od::kTargetVelocity, 0);
  s_.gravity_compensation = values_.slot(od::kGravityCompensation, 0);
  s_.tau_ext = values_.slot(od::kTauExtHatFiltered, 0);
  s_.errors_first = values_.slot(od::kCurrentErrors, 1);
  reset(false);
}

int64_t DriveNode::value(uint16_t index, uint8_t subindex) const { return values_[values_.slot(index, subindex)]; }

// NMT reset node (all objects) or reset communication (0x1000-0x1FFF), then boot-up.
void DriveNode::reset(bool communication_only) {
  values_.reset(communication_only);
  write_measurement();
  pdos_.rebuild();
  sdo_.reset();
  heartbeat_consumer_.stop();
  if (!communication_only) {
    previous_controlword_ = 0;
    torque_limited_ = false;
    recovery_requested_ = false;
    received_since_sync_ = false;
    mixed_modes_reported_ = false;
    followed_ = false;
    set_state(next_state(DriveState::kNotReadyToSwitchOn, 0, 0, 0));   // self-test done: switch on disabled
  }
  nmt_.boot_up();
}

void DriveNode::nmt_command(uint8_t command) {
  switch (nmt_.command(command)) {
    case NmtSlave::Reset::kNode: reset(false); break;
    case NmtSlave::Reset::kCommunication: reset(true); break;
    case NmtSlave::Reset::kNone: break;
  }
}

void DriveNode::receive_sync(const Frame& frame) {
  if (frame.dlc > 1) emcy_.send(kEmcySyncLength);   // SYNC carries no data or the 1-byte counter
}

void DriveNode::elapse(uint32_t microseconds) {
  nmt_.elapse(microseconds);
  // The master went silent: fault, like a lost FCI connection (generic + communication error).
  if (heartbeat_consumer_.elapse(microseconds)) enter_fault(kEmcyHeartbeat, -1, 0x11);
}

// ---------------------------------------------------------------- object dictionary glue
uint32_t DriveNode::write(int slot, int64_t value) {
  const Entry& e = values_.entry(slot);
  if (value < e.low) return abort::kValueTooLow;
  if (value > e.high) return abort::kValueTooHigh;
  if (const uint32_t code = pdos_.check_parameter(slot, value); code != 0) return code;
  if (e.index == od::kCobIdEmcy) {
    const uint32_t sync_cob_id = static_cast<uint32_t>(values_[values_.slot(od::kCobIdSync, 0)]);
    if (const uint32_t code = check_cob_id(static_cast<uint32_t>(values_[slot]), static_cast<uint32_t>(value), sync_cob_id); code != 0)
      return code;
  }
  store(slot, value);
  return 0;
}

void DriveNode::store(int slot, int64_t value) {
  values_[slot] = value;
  const Entry& e = values_.entry(slot);
  if (slot == s_.controlword) set_controlword(static_cast<uint16_t>(value));
  else if (slot == s_.mode) values_[s_.mode_display] = value;   // the mode changes at once
  else if (e.index == od::kAutomaticErrorRecovery) recovery_requested_ = true;
  else if (e.index == od::kProducerHeartbeatTime) nmt_.restart_heartbeat();
  else if (e.index == od::kConsumerHeartbeatTime) heartbeat_consumer_.stop();
  else if (PdoService::is_parameter(e.index)) pdos_.rebuild();
}

// ---------------------------------------------------------------- CiA 402
void DriveNode::sync_latch() {
  // A cycle after a fault or a quick stop, the robot's reaction is over (transitions 14 and 12).
  if (state_ == DriveState::kFaultReactionActive) set_state(DriveState::kFault);
  set_state(quick_stop_over(state_, static_cast<int>(values_[s_.quick_stop_option])));
  received_since_sync_ = pdos_.latch_sync();
}

void DriveNode::set_controlword(uint16_t controlword) {
  const DriveState before = state_;
  set_state(next_state(state_, controlword, previous_controlword_, static_cast<int>(values_[s_.quick_stop_option])));
  previous_controlword_ = controlword;
  if (before == DriveState::kFault && state_ == DriveState::kSwitchOnDisabled) {   // fault reset
    recovery_requested_ = true;
    emcy_.reset_errors();
  }
}

void DriveNode::set_state(DriveState state) {
  state_ = state;
  if (state != DriveState::kOperationEnabled) followed_ = false;   // enabled again, it waits for the robot's word
  values_[s_.statusword] = statusword_state_bits(state) | 0x0200   // bit 9 remote: the controlword is obeyed
                           | (torque_limited_ ? 0x0800 : 0)          // bit 11 internal limit active
                           | (followed_ ? 0x1000 : 0);               // bit 12: the drive follows the target
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

void DriveNode::update(const JointMeasurement& m, const rt::ErrorSet& errors, bool mixed_modes, bool motion) {
  measured_ = m;
  write_measurement();
  const bool in_mix = mixed_modes && state_ == DriveState::kOperationEnabled;
  if (in_mix && !mixed_modes_reported_) emcy_.send(kEmcyMixedModes);   // once per mix; the error register is unchanged
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
      else emcy_.send(emcy_code_of_error(i), i);
      first = false;
    }
  }
  // After a reflex the drive is in fault; otherwise the robot either acts on its targets or, if it
  // did until now, says that it stopped.
  const bool followed = state_ == DriveState::kOperationEnabled && motion;
  if (followed_ && !followed && state_ == DriveState::kOperationEnabled) emcy_.send(kEmcyTargetIgnored);
  followed_ = followed;
  set_state(state_);   // refresh the statusword's bits
}

void DriveNode::enter_fault(uint16_t emcy_code, int error, uint8_t register_bits) {
  set_state(fault(state_));
  emcy_.send(emcy_code, error, register_bits);
}

}  // namespace csp::can
