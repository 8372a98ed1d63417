// The NMT slave of a node (CiA 301 NMT state machine): its communication state, which the master's NMT
// commands set, and the heartbeat producer (0x1017) that sends that state periodically
// (CANopenNode's CO_NMT_Heartbeat).
#pragma once

#include <cstdint>
#include <vector>

#include "csp/can/frame.hpp"
#include "csp/can/object_values.hpp"

namespace csp::can {

enum class NmtState : uint8_t { kInitialising = 0x00, kStopped = 0x04, kOperational = 0x05, kPreOperational = 0x7F };
const char* nmt_state_name(NmtState state);

// NMT command specifiers (first byte of COB-ID 0x000).
inline constexpr uint8_t kNmtStart = 0x01, kNmtStop = 0x02, kNmtEnterPreOperational = 0x80, kNmtResetNode = 0x81,
                         kNmtResetCommunication = 0x82;

class NmtSlave {
 public:
  NmtSlave(uint8_t node_id, const ObjectValues& values, std::vector<Frame>& out);

  NmtState state() const { return state_; }

  // What an NMT command leaves to the node: the resets restore its objects, then call boot_up().
  enum class Reset { kNone, kNode, kCommunication };
  Reset command(uint8_t command);
  // Initialisation done: the boot-up message, then pre-operational; the heartbeat period starts.
  void boot_up();
  // A new producer heartbeat time: the period counts from now.
  void restart_heartbeat() { heartbeat_elapsed_us_ = 0; }
  // Sends the heartbeats that fall due.
  void elapse(uint32_t microseconds);

 private:
  uint8_t node_id_;
  const ObjectValues& values_;
  std::vector<Frame>& out_;
  int producer_time_slot_;   // 0x1017 [ms], 0 = no heartbeat
  NmtState state_ = NmtState::kInitialising;
  uint32_t heartbeat_elapsed_us_ = 0;
};

}  // namespace csp::can
