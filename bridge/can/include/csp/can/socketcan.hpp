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

// A frame handed out more than this after the kernel received it is late: a drive on a real bus
// would have acted on it a cycle (1 ms) later than it came.
inline constexpr int64_t kLateFrameNs = 1'000'000;

struct SocketCounters {
  uint64_t received = 0;
  uint64_t dropped = 0;       // frames the kernel dropped because the socket's receive queue was full (SO_RXQ_OVFL)
  uint64_t late = 0;          // received frames handed out more than kLateFrameNs after the kernel received them
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
  // kernel in batches (recvmmsg): one system call for a burst. Each comes with the kernel's
  // receive time (SO_TIMESTAMPNS: late frames are counted) and its count of frames dropped on this
  // socket so far (SO_RXQ_OVFL: a queue overrun shows with the next frame received).
  std::optional<Frame> receive();
  // Frames already read from the kernel and not handed out yet.
  bool pending() const { return next_ < batch_.size(); }
  const SocketCounters& counters() const { return counters_; }

 private:
  static constexpr int kBatch = 64;

  std::string interface_;
  int fd_ = -1;
  SocketCounters counters_;
  struct Received {
    Frame frame;
    int64_t kernel_ns;   // CLOCK_REALTIME when the kernel received it (0: unknown)
  };
  std::vector<Received> batch_;   // read, not yet handed out
  std::size_t next_ = 0;
};

// Waits up to `timeout_ns` until one of the sockets has a frame; returns whether one has.
bool wait_readable(const std::vector<SocketCan*>& sockets, int64_t timeout_ns);

}  // namespace csp::can
