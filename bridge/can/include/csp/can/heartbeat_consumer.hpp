// The heartbeat consumer of a node (CiA 301 heartbeat protocol; CANopenNode's CO_HBconsumer): watches
// the one node 0x1016 sub-index 1 names (node id in bits 16-22, time in ms in bits 0-15; time 0 =
// not watched). Watching starts with that node's first heartbeat.
#pragma once

#include <cstdint>

#include "csp/can/object_values.hpp"

namespace csp::can {

class HeartbeatConsumer {
 public:
  explicit HeartbeatConsumer(const ObjectValues& values);

  void receive(uint8_t producer);
  // True once when the watched node's heartbeat is overdue; then it waits for a first one again.
  bool elapse(uint32_t microseconds);
  // A reset or a new 0x1016: wait for a first heartbeat again.
  void stop() { active_ = false; elapsed_us_ = 0; }

 private:
  const ObjectValues& values_;
  int consumer_time_slot_;   // 0x1016 sub-index 1
  bool active_ = false;      // the watched node's first heartbeat arrived
  uint32_t elapsed_us_ = 0;
};

}  // namespace csp::can
