// A SocketCAN raw socket on one interface (vcan0, can0, ...): classic 11-bit data frames in and
// out, non-blocking. Linux only; the host needs AF_CAN (modules can, can_raw) and the interface
// up. Every failure names the interface and what to do.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "csp/can/frame.hpp"

namespace csp::can {

struct SocketCounters {
  uint64_t received = 0;
  uint64_t sent = 0;
  uint64_t skipped = 0;       // received frames that are not classic 11-bit data frames (RTR, 29-bit, error)
  uint64_t send_failures = 0; // frames the interface would not take (queue full, interface down)
};

class SocketCan {
 public:
  // Opens and binds a raw CAN socket; std::runtime_error naming the interface and the reason.
  explicit SocketCan(const std::string& interface);
  ~SocketCan();
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;

  const std::string& interface() const { return interface_; }
  int fd() const { return fd_; }
  // Sends one frame; a full queue is waited for up to 1 ms, then the frame counts as a failure.
  bool send(const Frame& frame);
  // The next classic data frame waiting, or nothing (never blocks). Frames are read from the
  // kernel in batches (recvmmsg): one system call for a burst.
  std::optional<Frame> receive();
  // Frames already read from the kernel and not handed out yet.
  bool pending() const { return next_ < batch_.size(); }
  const SocketCounters& counters() const { return counters_; }

 private:
  static constexpr int kBatch = 64;

  std::string interface_;
  int fd_ = -1;
  SocketCounters counters_;
  std::vector<Frame> batch_;   // read, not yet handed out
  std::size_t next_ = 0;
};

// Waits up to `timeout_ns` until one of the sockets has a frame; returns whether one has.
bool wait_readable(const std::vector<SocketCan*>& sockets, int64_t timeout_ns);

}  // namespace csp::can
