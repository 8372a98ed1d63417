#include "csp/can/nmt_slave.hpp"

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

NmtSlave::NmtSlave(uint8_t node_id, const ObjectValues& values, std::vector<Frame>& out)
    : node_id_(node_id), values_(values), out_(out), producer_time_slot_(values.slot(od::kProducerHeartbeatTime, 0)) {}

NmtSlave::Reset NmtSlave::command(uint8_t command) {
  switch (command) {
    case kNmtStart: state_ = NmtState::kOperational; break;
    case kNmtStop: state_ = NmtState::kStopped; break;
    case kNmtEnterPreOperational: state_ = NmtState::kPreOperational; break;
    case kNmtResetNode: return Reset::kNode;
    case kNmtResetCommunication: return Reset::kCommunication;
    default: break;   // unknown command specifiers are ignored (CiA 301)
  }
  return Reset::kNone;
}

void NmtSlave::boot_up() {
  state_ = NmtState::kInitialising;
  heartbeat_elapsed_us_ = 0;
  out_.push_back(make_frame(kHeartbeat + node_id_, {0x00}));   // boot-up message
  state_ = NmtState::kPreOperational;
}

void NmtSlave::elapse(uint32_t microseconds) {
  const uint32_t producer_us = static_cast<uint32_t>(values_[producer_time_slot_]) * 1000;
  if (producer_us == 0) return;
  heartbeat_elapsed_us_ += microseconds;
  while (heartbeat_elapsed_us_ >= producer_us) {
    heartbeat_elapsed_us_ -= producer_us;
    out_.push_back(make_frame(kHeartbeat + node_id_, {static_cast<uint8_t>(state_)}));
  }
}

}  // namespace csp::can
