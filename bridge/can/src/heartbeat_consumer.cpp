#include "csp/can/heartbeat_consumer.hpp"

namespace csp::can {

HeartbeatConsumer::HeartbeatConsumer(const ObjectValues& values)
    : values_(values), consumer_time_slot_(values.slot(od::kConsumerHeartbeatTime, 1)) {}

void HeartbeatConsumer::receive(uint8_t producer) {
  const uint32_t consumer = static_cast<uint32_t>(values_[consumer_time_slot_]);
  if (((consumer >> 16) & 0x7F) != producer || (consumer & 0xFFFF) == 0) return;
  active_ = true;
  elapsed_us_ = 0;
}

bool HeartbeatConsumer::elapse(uint32_t microseconds) {
  const uint32_t consumer_us = (static_cast<uint32_t>(values_[consumer_time_slot_]) & 0xFFFF) * 1000;
  if (!active_ || consumer_us == 0) return false;
  elapsed_us_ += microseconds;
  if (elapsed_us_ <= consumer_us) return false;
  active_ = false;
  return true;
}

}  // namespace csp::can
