#include "csp/fci/serve.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <stdexcept>
#include <utility>

#include "csp/rt/scenario.hpp"

namespace csp::fci {
namespace {

using rt::monotonic_ns;

// A socket file descriptor, closed with its owner.
class Socket {
 public:
  Socket() = default;
  explicit Socket(int fd) : fd_(fd) {}
  Socket(Socket&& other) noexcept : fd_(other.release()) {}
  Socket& operator=(Socket&& other) noexcept {
    reset(other.release());
    return *this;
  }
  ~Socket() { reset(); }
  int fd() const { return fd_; }
  bool open() const { return fd_ >= 0; }
  void reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_ = -1;
};

std::string endpoint(const sockaddr_in& a) {
  char text[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &a.sin_addr, text, sizeof(text));
  return std::string(text) + ":" + std::to_string(ntohs(a.sin_port));
}

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what + ": " + std::strerror(errno)); }

// One TCP port of the robot and its one client, with the UDP socket of its state messages (and,
// on the command port, of the commands). The server behind it judges every byte; this class only
// moves them. While a client is connected the port does not listen: a second client's connection
// is refused (libfranka: "Connection to FCI refused") instead of left waiting for an answer.
class Port {
 public:
  using Diagnostic = std::function<void(const std::string&)>;

  Port(const sockaddr_in& address, uint16_t port, PortServer& server, std::string name, Diagnostic diagnostic)
      : address_(address), server_(server), name_(std::move(name)), diagnostic_(std::move(diagnostic)) {
    address_.sin_port = htons(port);
    udp_ = Socket(::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
    if (!udp_.open()) fail("UDP socket");
    sockaddr_in udp_address = address;
    udp_address.sin_port = 0;   // libfranka answers to wherever the state came from
    if (::bind(udp_.fd(), reinterpret_cast<const sockaddr*>(&udp_address), sizeof(udp_address)) != 0)
      fail("cannot bind a UDP socket to " + endpoint(udp_address));
    listen();
  }

  // The socket to wait on for the TCP side: the client's, or the listener's.
  int tcp_fd() const { return client_.open() ? client_.fd() : listener_.fd(); }
  int udp_fd() const { return udp_.fd(); }

  // The TCP side is readable: a new client, or bytes (or the end) of the connected one.
  void on_tcp_readable() {
    if (!client_.open()) return accept_client();
    uint8_t buffer[4096];
    const ssize_t n = ::recv(client_.fd(), buffer, sizeof(buffer), MSG_DONTWAIT);
    if (n == 0) return drop_client("disconnected");
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
      return drop_client(std::string("lost: ") + std::strerror(errno));
    }
    if (!server_.receive_tcp(buffer, static_cast<std::size_t>(n))) drop_ = true;
    if (drop_) drop_client("disconnected by the robot");
  }

  // Whether a UDP packet came from the connected client's port.
  bool from_client(const sockaddr_in& from) const {
    const std::optional<uint16_t> port = server_.client_udp_port();
    return client_.open() && port && from.sin_addr.s_addr == client_address_.sin_addr.s_addr && ntohs(from.sin_port) == *port;
  }

  // Sends a state message to the client (once it has connected). A full socket buffer loses it, as
  // a full network would; the next one follows.
  void send_udp(const void* data, std::size_t size) const {
    const std::optional<uint16_t> port = server_.client_udp_port();
    if (!port || !client_.open()) return;
    sockaddr_in to = client_address_;
    to.sin_port = htons(*port);
    ::sendto(udp_.fd(), data, size, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
  }

 private:
  void listen() {
    listener_ = Socket(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
    if (!listener_.open()) fail("TCP socket");
    const int yes = 1;
    ::setsockopt(listener_.fd(), SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
    if (::bind(listener_.fd(), reinterpret_cast<const sockaddr*>(&address_), sizeof(address_)) != 0)
      fail("cannot listen on " + endpoint(address_));
    if (::listen(listener_.fd(), 1) != 0) fail("cannot listen on " + endpoint(address_));
  }

  void accept_client() {
    sockaddr_in from{};
    socklen_t length = sizeof(from);
    Socket client(::accept4(listener_.fd(), reinterpret_cast<sockaddr*>(&from), &length, SOCK_NONBLOCK | SOCK_CLOEXEC));
    if (!client.open()) return;   // gone before it was accepted
    const int yes = 1;
    ::setsockopt(client.fd(), IPPROTO_TCP, TCP_NODELAY, &yes, sizeof(yes));
    client_ = std::move(client);
    client_address_ = from;
    listener_.reset();
    drop_ = false;
    diagnostic_(name_ + "client connected from " + endpoint(from));
    server_.open_connection([this](const std::vector<uint8_t>& bytes) { send_tcp(bytes); });
  }

  void drop_client(const std::string& why) {
    diagnostic_(name_ + "client " + endpoint(client_address_) + " " + why);
    server_.close_connection();
    client_.reset();
    listen();
  }

  // Blocking until sent or 2 s passed (a client that takes no bytes is dropped): replies are small
  // but for the model library.
  void send_tcp(const std::vector<uint8_t>& bytes) {
    std::size_t sent = 0;
    const int64_t give_up = monotonic_ns() + 2'000'000'000;
    while (sent < bytes.size() && !drop_) {
      const ssize_t n = ::send(client_.fd(), bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        sent += static_cast<std::size_t>(n);
      } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && monotonic_ns() < give_up) {
        pollfd fd{client_.fd(), POLLOUT, 0};
        ::poll(&fd, 1, 10);
      } else {
        drop_ = true;
      }
    }
  }

  sockaddr_in address_;
  PortServer& server_;
  std::string name_;   // prefix of its diagnostics ("" for the robot, "gripper: ")
  Diagnostic diagnostic_;
  Socket listener_, client_, udp_;
  sockaddr_in client_address_{};
  bool drop_ = false;
};

sockaddr_in ipv4_address(const std::string& address) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1) throw std::runtime_error("--address " + address + ": not an IPv4 address");
  return a;
}

// The robot on the network: its command port with the 1 kHz exchange, and its devices' ports.
class Network : public rt::MessageBus {
 public:
  Network(rt::Emulator& robot, const FciServeOptions& options)
      : options_(options),
        server_(robot, options.version, options.model_library, [this](const std::string& line) { diagnose(line); }, options.faults),
        robot_port_(ipv4_address(options.address), kCommandPort, server_, "", [this](const std::string& line) { diagnose(line); }) {
    const auto diagnostic = [this](const std::string& line) { diagnose(line); };
    if (options.hand) {
      gripper_ = std::make_unique<GripperServer>(robot, rt::Hand(*options.hand), diagnostic);
      add_device(*gripper_, kGripperPort, "gripper: ");
    }
    if (options.vacuum_gripper) {
      vacuum_gripper_ = std::make_unique<VacuumGripperServer>(robot, rt::VacuumPump(*options.vacuum_gripper), diagnostic);
      add_device(*vacuum_gripper_, kVacuumGripperPort, "vacuum gripper: ");
    }
  }

  FciServer& server() { return server_; }
  const GripperServer* gripper() const { return gripper_.get(); }
  const VacuumGripperServer* vacuum_gripper() const { return vacuum_gripper_.get(); }
  uint64_t foreign_packets() const { return foreign_packets_; }

  // MessageBus
  void receive_for(int64_t wait_ns) override;
  bool in_session() const override { return server_.commands_flowing(); }
  bool answered() const override { return server_.answered(); }
  void robot_cycle(rt::CycleDriver& driver) override;
  void repeat_state() override { send_state(); }
  bool stopped() const override { return options_.stop && options_.stop->load(); }

  void send_state() {
    const RobotStatePacket packet = server_.state_packet();
    if (server_.in_motion() && !state_sent_ns_) state_sent_ns_ = monotonic_ns();
    robot_port_.send_udp(&packet, sizeof(packet));
  }

 private:
  void receive_commands() {
    // A packet larger than any command is read whole, so that its size is judged, not truncated.
    uint8_t buffer[2048];
    for (;;) {
      sockaddr_in from{};
      socklen_t length = sizeof(from);
      const ssize_t n = ::recvfrom(robot_port_.udp_fd(), buffer, sizeof(buffer), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &length);
      if (n < 0) return;
      if (!robot_port_.from_client(from)) {
        ++foreign_packets_;
        continue;
      }
      server_.receive_udp(buffer, static_cast<std::size_t>(n));
      if (server_.answered() && state_sent_ns_ && !answered_ns_) answered_ns_ = monotonic_ns();
    }
  }

  void diagnose(const std::string& line) const {
    if (options_.diagnostic) options_.diagnostic(line);
  }

  const FciServeOptions& options_;
  FciServer server_;
  Port robot_port_;
  // The devices and their ports (their UDP sockets only send state messages).
  struct Device {
    DeviceServerBase* server;
    std::unique_ptr<Port> port;
  };
  void add_device(DeviceServerBase& server, uint16_t port, const std::string& name) {
    devices_.push_back({&server, std::make_unique<Port>(ipv4_address(options_.address), port, server, name,
                                                        [this](const std::string& line) { diagnose(line); })});
  }
  std::unique_ptr<GripperServer> gripper_;
  std::unique_ptr<VacuumGripperServer> vacuum_gripper_;
  std::vector<Device> devices_;
  uint64_t foreign_packets_ = 0;
  std::optional<int64_t> state_sent_ns_, answered_ns_;   // the round trip of a motion's cycle
};

void Network::receive_for(int64_t wait_ns) {
  pollfd fds[4] = {{robot_port_.udp_fd(), POLLIN, 0}, {robot_port_.tcp_fd(), POLLIN, 0}, {-1, POLLIN, 0}, {-1, POLLIN, 0}};
  for (std::size_t d = 0; d < devices_.size(); ++d) fds[2 + d].fd = devices_[d].port->tcp_fd();
  const timespec timeout{wait_ns / 1'000'000'000, wait_ns % 1'000'000'000};
  if (::ppoll(fds, 4, &timeout, nullptr) <= 0) return;
  const short ready = POLLIN | POLLHUP | POLLERR;
  if (fds[0].revents & POLLIN) receive_commands();
  if (fds[1].revents & ready) robot_port_.on_tcp_readable();
  for (std::size_t d = 0; d < devices_.size(); ++d)
    if (fds[2 + d].revents & ready) devices_[d].port->on_tcp_readable();
}

// One robot cycle: the server steps with the command that answered the state (or none), the new
// state goes to the client; the hand moves with it.
void Network::robot_cycle(rt::CycleDriver& driver) {
  const bool lost = server_.in_motion() && !server_.answered();
  if (state_sent_ns_ && answered_ns_) driver.add_round_trip_ns(*answered_ns_ - *state_sent_ns_);
  state_sent_ns_.reset();
  answered_ns_.reset();
  server_.step();
  for (const Device& device : devices_)
    if (const std::optional<std::vector<uint8_t>> state = device.server->step()) device.port->send_udp(state->data(), state->size());
  driver.count_cycle(lost);
  send_state();
  if (options_.after_cycle) options_.after_cycle(server_.emulator().state(), server_.last_cycle());
}

}  // namespace

FciServeReport serve_fci(rt::Emulator& robot, const FciServeOptions& options) {
  rt::BusPacing pacing;
  if (options.duration) {
    if (!(*options.duration > 0.0) || *options.duration > rt::kMaxDuration)
      throw std::invalid_argument("duration: expected a positive number of seconds");
    pacing.cycles = static_cast<uint64_t>(std::llround(*options.duration / rt::kDeltaT));
  }
  if (!(options.lockstep_timeout > 0.0 && options.lockstep_timeout <= 3600.0))
    throw std::invalid_argument("lockstep timeout: expected a positive number of seconds, at most 3600");
  pacing.lockstep_timeout = options.lockstep_timeout;
  Network network(robot, options);
  rt::CycleDriver driver(options.clock);
  if (options.listening) options.listening();
  network.send_state();
  rt::run_bus_cycles(network, driver, pacing);

  FciServeReport report;
  report.timing = driver.report();
  report.counters = network.server().counters();
  report.emulator = robot.counters();
  report.foreign_packets = network.foreign_packets();
  if (network.gripper()) report.gripper = network.gripper()->counters();
  if (network.vacuum_gripper()) report.vacuum_gripper = network.vacuum_gripper()->counters();
  report.last_reflex = robot.reflex_reason();
  return report;
}

}  // namespace csp::fci
