#include "csp/can/socketcan.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace csp::can {
namespace {

std::runtime_error failure(const std::string& interface, const std::string& what, int error) {
  std::string hint;
  if (error == EAFNOSUPPORT || error == EPROTONOSUPPORT)
    hint = " (this kernel has no SocketCAN: load the modules can and can_raw, e.g. `modprobe can_raw`)";
  else if (error == ENODEV)
    hint = " (no such interface: for a virtual bus `ip link add dev " + interface + " type vcan && ip link set " + interface + " up`)";
  else if (error == ENETDOWN)
    hint = " (the interface is down: `ip link set " + interface + " up`)";
  return std::runtime_error("CAN interface " + interface + ": " + what + ": " + std::strerror(error) + hint);
}

}  // namespace

SocketCan::SocketCan(const std::string& interface) : interface_(interface) {
  if (interface.empty() || interface.size() >= IFNAMSIZ)
    throw std::runtime_error("CAN interface `" + interface + "`: a name of 1 to " + std::to_string(IFNAMSIZ - 1) + " characters expected");
  fd_ = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) throw failure(interface, "cannot open a raw CAN socket", errno);
  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) {
    const int error = errno;
    close(fd_);
    throw failure(interface, "not found", error);
  }
  // A deep receive queue: a burst of frames (a master's start-up, a flood) waits instead of
  // being dropped (SO_RCVBUFFORCE needs CAP_NET_ADMIN; without it the system's maximum applies).
  const int queue_bytes = 8 << 20;
  if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &queue_bytes, sizeof queue_bytes) != 0)
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &queue_bytes, sizeof queue_bytes);
  // Frames lost to a full queue anyway are counted (the kernel's drop count with every frame), and
  // each frame carries its receive time.
  const int on = 1;
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
  setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  if (bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    const int error = errno;
    close(fd_);
    throw failure(interface, "cannot bind", error);
  }
}

SocketCan::~SocketCan() {
  if (fd_ >= 0) close(fd_);
}

bool SocketCan::send(const Frame& frame) {
  can_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.can_dlc = frame.dlc;
  std::memcpy(raw.data, frame.data.data(), 8);
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (write(fd_, &raw, sizeof raw) == static_cast<ssize_t>(sizeof raw)) {
      ++counters_.sent;
      return true;
    }
    if (errno != ENOBUFS && errno != EAGAIN) break;
    // The interface's queue is full: give it a millisecond.
    pollfd p{fd_, POLLOUT, 0};
    const timespec wait{0, 1'000'000};
    ppoll(&p, 1, &wait, nullptr);
  }
  ++counters_.send_failures;
  return false;
}

namespace {
int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}
}  // namespace

std::optional<Frame> SocketCan::receive() {
  while (next_ == batch_.size()) {
    can_frame raw[kBatch];
    iovec io[kBatch];
    mmsghdr messages[kBatch];
    // Room for the two ancillary items of each frame: the drop count and the receive time.
    struct Control {
      alignas(cmsghdr) char bytes[CMSG_SPACE(sizeof(uint32_t)) + CMSG_SPACE(sizeof(timespec))];
    } control[kBatch];
    for (int i = 0; i < kBatch; ++i) {
      io[i] = iovec{&raw[i], sizeof raw[i]};
      messages[i] = mmsghdr{};
      messages[i].msg_hdr.msg_iov = &io[i];
      messages[i].msg_hdr.msg_iovlen = 1;
      messages[i].msg_hdr.msg_control = control[i].bytes;
      messages[i].msg_hdr.msg_controllen = sizeof control[i].bytes;
    }
    const int n = recvmmsg(fd_, messages, kBatch, MSG_DONTWAIT, nullptr);
    if (n <= 0) return std::nullopt;
    batch_.clear();
    next_ = 0;
    for (int i = 0; i < n; ++i) {
      int64_t kernel_ns = 0;
      for (cmsghdr* c = CMSG_FIRSTHDR(&messages[i].msg_hdr); c; c = CMSG_NXTHDR(&messages[i].msg_hdr, c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SO_RXQ_OVFL) {
          uint32_t drops = 0;   // the socket's drops so far, when this frame was queued
          std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
          counters_.dropped = std::max<uint64_t>(counters_.dropped, drops);
        } else if (c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec t{};
          std::memcpy(&t, CMSG_DATA(c), sizeof t);
          kernel_ns = int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
        }
      }
      const can_frame& r = raw[i];
      if (messages[i].msg_len != sizeof r || (r.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) || r.can_dlc > 8) {
        ++counters_.skipped;
        continue;
      }
      Frame frame;
      frame.id = r.can_id & CAN_SFF_MASK;
      frame.dlc = r.can_dlc;
      std::memcpy(frame.data.data(), r.data, 8);
      batch_.push_back({frame, kernel_ns});
    }
  }
  ++counters_.received;
  const Received& r = batch_[next_++];
  if (r.kernel_ns != 0 && realtime_ns() - r.kernel_ns > kLateFrameNs) ++counters_.late;
  return r.frame;
}

bool wait_readable(const std::vector<SocketCan*>& sockets, int64_t timeout_ns) {
  std::vector<pollfd> fds;
  for (const SocketCan* s : sockets) {
    if (s->pending()) return true;
    fds.push_back(pollfd{s->fd(), POLLIN, 0});
  }
  timeout_ns = std::max<int64_t>(timeout_ns, 0);
  const timespec timeout{timeout_ns / 1'000'000'000, timeout_ns % 1'000'000'000};
  return ppoll(fds.data(), fds.size(), &timeout, nullptr) > 0;
}

}  // namespace csp::can
