// csp_bridge_bench: the network front ends' figures side by side, in one run (docs/bridge.md,
// docs/fci.md "Figures"), on both clocks:
//   - LCM: the example controller csp_lcm_float in another process, over loopback UDP multicast;
//   - FCI, libfranka: serve_fci with libfranka 0.13.3's communication_test as the client process
//     (built by tests/fci; skipped, and said so, when it is not there);
//   - FCI, minimal client: our own few lines of client (a thread of this process) that holds the
//     arm in a joint position motion, so that the server's own round trip is seen without
//     libfranka's; it also measures, on its side, a command sent -> the next state received.
// Then the ratios FCI / LCM, and the LCM log write rate.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <thread>

#include "bridge_support.hpp"
#include "csp/bridge/serve.hpp"
#include "csp/fci/model_library.hpp"
#include "csp/fci/serve.hpp"
#include "csp/rt/statistics.hpp"

namespace {

using namespace std::chrono_literals;
using csp::rt::Clock;
using csp::rt::Percentiles;

constexpr double kSessionSeconds = 10.0;          // LCM controller's run; the minimal client's motion
constexpr uint64_t kMinimalClientCycles = 10000;

// CPU time [s] of this process (RUSAGE_SELF) or of its ended children (RUSAGE_CHILDREN).
double cpu_seconds(int who) {
  rusage usage{};
  getrusage(who, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

// What one session measured, for the table at the end.
struct SessionFigures {
  std::string name;
  uint64_t cycles = 0, motion_cycles = 0, lost_commands = 0;
  double motion_seconds = 0.0;     // wall time of the motion (session) cycles
  Percentiles round_trip_us;       // server side: state sent -> its command received
  std::optional<Percentiles> command_to_state_us;   // client side: command sent -> next state received
  uint64_t stalls = 0;             // FCI lockstep: motion cycles that waited the whole lockstep timeout
  double stall_seconds = 0.0;
  double cycles_per_second() const { return motion_seconds > 0.0 ? static_cast<double>(motion_cycles) / motion_seconds : 0.0; }
  double cycles_per_second_without_stalls() const {
    return motion_seconds > stall_seconds ? static_cast<double>(motion_cycles - stalls) / (motion_seconds - stall_seconds) : 0.0;
  }
};

void print_round_trip(const char* what, const Percentiles& p) {
  std::printf("  %s [us]: p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f (%zu)\n", what, p.p50, p.p99, p.p999, p.max, p.count);
}

SessionFigures run_lcm_session(const char* title, Clock clock, double seconds, int port_offset) {
  const std::string url = csp::test::unique_lcm_url(port_offset);
  csp::bridge::ServeOptions options;
  options.clock = clock;
  options.duration = seconds + 0.2;
  options.lcm_url = url;
  options.wait_for_controller = clock == Clock::kLockstep;
  options.quiet = true;
  csp::test::Process controller({CSP_LCM_FLOAT, "--lcm-url", url, "--duration", std::to_string(seconds)},
                                csp::test::temp_path("bench-controller.out"));
  const double self_cpu = cpu_seconds(RUSAGE_SELF), children_cpu = cpu_seconds(RUSAGE_CHILDREN);
  const csp::rt::Scenario scenario = csp::rt::load_scenario(csp::rt::default_scenario_path());
  csp::rt::Emulator robot(scenario.emulator);
  const csp::bridge::ServeReport r = csp::bridge::serve(robot, scenario, options);
  const int exit_code = controller.wait(10s);
  SessionFigures figures;
  figures.name = "LCM, csp_lcm_float";
  figures.cycles = r.timing.cycles;
  figures.motion_cycles = r.emulator.motion_cycles;
  figures.lost_commands = r.emulator.lost_commands;
  figures.motion_seconds = r.motion_wall_seconds;
  figures.round_trip_us = r.timing.round_trip_us;
  std::printf("%s: %llu cycles in %.3f s; session %llu cycles in %.3f s = %.0f cycles/s; lost commands %llu; overruns %llu\n",
              title, static_cast<unsigned long long>(r.timing.cycles), r.timing.wall_seconds,
              static_cast<unsigned long long>(figures.motion_cycles), figures.motion_seconds, figures.cycles_per_second(),
              static_cast<unsigned long long>(figures.lost_commands), static_cast<unsigned long long>(r.timing.overruns));
  print_round_trip("round trip state -> command", r.timing.round_trip_us);
  std::printf("  CPU: server %.3f s, controller process %.3f s (exit code %d)\n", cpu_seconds(RUSAGE_SELF) - self_cpu,
              cpu_seconds(RUSAGE_CHILDREN) - children_cpu, exit_code);
  return figures;
}

// --- FCI -------------------------------------------------------------------------------------

// Serves the FR3 of configs/scenarios/libfranka_fr3.yaml over the FCI (version 7) on `address`
// until `stop` is set, as `csp fci` does; `start_client` runs once the command port listens.
// `figures`: the wall time of the cycles of a motion (FciServeReport has no such figure) and its
// stalls, the cycles that waited for the whole lockstep timeout (a command that never came).
csp::fci::FciServeReport serve_fr3(Clock clock, const std::string& address, const std::atomic<bool>& stop,
                                   const std::function<void()>& start_client, SessionFigures& figures) {
  const csp::rt::Scenario scenario = csp::rt::load_scenario(CSP_SOURCE_DIR "/configs/scenarios/libfranka_fr3.yaml");
  csp::rt::Emulator robot(scenario.emulator);
  csp::fci::FciServeOptions options;
  options.address = address;
  options.version = csp::fci::kFr3Version;
  options.clock = clock;
  options.faults = scenario.command_faults;
  if (scenario.has_hand) options.hand = scenario.hand;
  options.model_library = [&robot] { return csp::fci::model_library_for(robot.internal_model().parameters()); };
  options.stop = &stop;
  options.listening = start_client;
  options.diagnostic = [](const std::string& line) { std::printf("  (csp fci: %s)\n", line.c_str()); };
  int64_t previous_cycle_ns = csp::rt::monotonic_ns();
  options.after_cycle = [&](const csp::rt::RobotState& state, const csp::rt::CycleInfo& cycle) {
    const int64_t now = csp::rt::monotonic_ns();
    const double seconds = static_cast<double>(now - previous_cycle_ns) * 1e-9;
    if (state.robot_mode == csp::rt::RobotMode::kMove || cycle.command_received) {
      figures.motion_seconds += seconds;
      if (clock == Clock::kLockstep && seconds >= options.lockstep_timeout) {
        ++figures.stalls;
        figures.stall_seconds += seconds;
      }
    }
    previous_cycle_ns = now;
  };
  const csp::fci::FciServeReport r = csp::fci::serve_fci(robot, options);
  figures.cycles = r.timing.cycles;
  figures.motion_cycles = r.emulator.motion_cycles;
  figures.lost_commands = r.emulator.lost_commands;
  figures.round_trip_us = r.timing.round_trip_us;
  return r;
}

void print_fci_session(const char* title, const csp::fci::FciServeReport& r, const SessionFigures& figures) {
  const csp::fci::FciCounters& c = r.counters;
  std::printf("%s: %llu cycles in %.3f s; %llu motions, %llu motion cycles in %.3f s = %.0f cycles/s; lost commands %llu; "
              "overruns %llu; stale %llu, rejected %llu command packets\n",
              title, static_cast<unsigned long long>(r.timing.cycles), r.timing.wall_seconds,
              static_cast<unsigned long long>(c.motions), static_cast<unsigned long long>(figures.motion_cycles), figures.motion_seconds,
              figures.cycles_per_second(), static_cast<unsigned long long>(figures.lost_commands),
              static_cast<unsigned long long>(r.timing.overruns), static_cast<unsigned long long>(c.stale_commands),
              static_cast<unsigned long long>(c.rejected_commands));
  if (figures.stalls > 0)
    std::printf("  %llu motion cycles waited the whole lockstep timeout (%.3f s); without them %.0f cycles/s\n",
                static_cast<unsigned long long>(figures.stalls), figures.stall_seconds, figures.cycles_per_second_without_stalls());
  print_round_trip("round trip state -> command (server)", r.timing.round_trip_us);
}

// libfranka 0.13.3's communication_test (a move to its start pose, then 10 s of zero torques) as
// the client process, with /sys/kernel/realtime faked (docs/fci-client-builds.md).
std::optional<SessionFigures> run_libfranka_session(const char* title, Clock clock, const std::string& address) {
  const std::string example = CSP_FCI_COMMUNICATION_TEST;
  if (example.empty() || !std::filesystem::exists(example)) {
    std::printf("%s: skipped, libfranka 0.13.3's communication_test is not built (%s; build csp_vendored_libfranka "
                "with CSP_BUILD_TESTS=ON)\n",
                title, example.empty() ? "CSP_BUILD_TESTS is off" : example.c_str());
    return std::nullopt;
  }
  const std::string fake_sys_kernel = csp::test::temp_path("sys-kernel");
  std::filesystem::create_directories(fake_sys_kernel);
  std::ofstream(fake_sys_kernel + "/realtime") << "1\n";
  const std::string output = csp::test::temp_path("communication_test.out");
  std::atomic<bool> stop = false;
  std::optional<csp::test::Process> client;
  std::thread watcher;
  int exit_code = -1;
  const auto start_client = [&] {
    // stdin from /dev/null: its "Press Enter" returns at once.
    client.emplace(std::vector<std::string>{"/usr/bin/unshare", "--mount", "sh", "-c",
                                            "mount --bind \"$0\" /sys/kernel && exec \"$@\" < /dev/null", fake_sys_kernel,
                                            example, address},
                   output);
    watcher = std::thread([&] {
      exit_code = client->wait(120s);
      stop = true;
    });
  };
  SessionFigures figures;
  figures.name = "FCI, libfranka communication_test";
  const double self_cpu = cpu_seconds(RUSAGE_SELF), children_cpu = cpu_seconds(RUSAGE_CHILDREN);
  const csp::fci::FciServeReport r = serve_fr3(clock, address, stop, start_client, figures);
  if (watcher.joinable()) watcher.join();
  print_fci_session(title, r, figures);
  std::string success_rate = "no 'Avg:' line";
  std::ifstream lines(output);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("Avg: ", 0) == 0) success_rate = line.substr(5);
  std::printf("  CPU: server %.3f s, client process %.3f s (exit code %d, its average success rate %s)\n",
              cpu_seconds(RUSAGE_SELF) - self_cpu, cpu_seconds(RUSAGE_CHILDREN) - children_cpu, exit_code,
              success_rate.c_str());
  if (exit_code != 0) std::printf("  its output (%s):\n%s\n", output.c_str(), client->output().c_str());
  std::filesystem::remove_all(fake_sys_kernel);
  std::filesystem::remove(output);
  return figures;
}

// The minimal client: TCP Connect, Move (joint impedance, joint position), then every motion state
// answered at once with a command holding q_d and echoing its message_id; the last one finishes
// the motion. It measures the time from each command's send to the next state's arrival.
class MinimalClient {
 public:
  explicit MinimalClient(const std::string& address) {
    tcp_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    udp_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in robot{};
    robot.sin_family = AF_INET;
    robot.sin_port = htons(csp::fci::kCommandPort);
    inet_pton(AF_INET, address.c_str(), &robot.sin_addr);
    if (::connect(tcp_, reinterpret_cast<const sockaddr*>(&robot), sizeof(robot)) != 0) fail("connect to " + address);
    const int yes = 1;
    ::setsockopt(tcp_, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof(yes));
    sockaddr_in any{};   // as libfranka: any address, a port of the kernel's choice
    any.sin_family = AF_INET;
    socklen_t length = sizeof(any);
    if (::bind(udp_, reinterpret_cast<const sockaddr*>(&any), sizeof(any)) != 0 ||
        ::getsockname(udp_, reinterpret_cast<sockaddr*>(&any), &length) != 0)
      fail("UDP socket");
    udp_port_ = ntohs(any.sin_port);
  }
  ~MinimalClient() {
    ::close(tcp_);
    ::close(udp_);
  }
  MinimalClient(const MinimalClient&) = delete;
  MinimalClient& operator=(const MinimalClient&) = delete;

  // Runs one motion of `cycles` commands; returns command sent -> next state received.
  Percentiles hold(uint64_t cycles) {
    using csp::fci::Command;
    using csp::fci::Status;
    request(Command::kConnect, csp::fci::ConnectRequest{csp::fci::kFr3Version, udp_port_});
    expect_status(Command::kConnect, Status::kSuccess, sizeof(csp::fci::Version));
    csp::fci::MoveRequest move{};
    move.controller_mode = static_cast<uint32_t>(csp::fci::MoveControllerMode::kJointImpedance);
    move.motion_generator_mode = static_cast<uint32_t>(csp::fci::MoveMotionGeneratorMode::kJointPosition);
    request(Command::kMove, move);
    expect_status(Command::kMove, Status::kMotionStarted, 0);

    // The motion runs from the newest state, whose id the server expects in the first command
    // (it may have been sent before the Move, showing no motion yet).
    csp::fci::RobotStatePacket state = receive_state();
    for (pollfd p{udp_, POLLIN, 0}; ::poll(&p, 1, 0) == 1;) state = receive_state();
    csp::rt::DurationHistogram command_to_state_us;
    for (uint64_t answered = 1;; ++answered) {
      csp::fci::RobotCommandPacketV7 command{};
      command.message_id = state.message_id;
      command.motion.q_c = state.q_d;
      command.motion.motion_generation_finished = answered == cycles ? 1 : 0;
      if (::sendto(udp_, &command, sizeof(command), 0, reinterpret_cast<const sockaddr*>(&robot_udp_), sizeof(robot_udp_)) !=
          static_cast<ssize_t>(sizeof(command)))
        fail("UDP send");
      if (answered == cycles) break;
      const int64_t command_sent_ns = csp::rt::monotonic_ns();
      state = receive_state();
      command_to_state_us.add(static_cast<double>(csp::rt::monotonic_ns() - command_sent_ns) * 1e-3);
    }
    expect_status(Command::kMove, Status::kSuccess, 0);   // the motion's end
    return command_to_state_us.percentiles();
  }

 private:
  [[noreturn]] static void fail(const std::string& what) {
    throw std::runtime_error("minimal FCI client: " + what + ": " + std::strerror(errno));
  }

  // Waits up to 5 s for `fd` to be readable.
  static void wait_readable(int fd, const char* what) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) throw std::runtime_error(std::string("minimal FCI client: no ") + what + " within 5 s");
  }

  template <typename Request>
  void request(csp::fci::Command command, const Request& payload) {
    const csp::fci::MessageHeader header{csp::fci::command_code(command, csp::fci::kFr3Version), ++command_id_,
                                         static_cast<uint32_t>(sizeof(header) + sizeof(payload))};
    uint8_t bytes[sizeof(header) + sizeof(payload)];
    std::memcpy(bytes, &header, sizeof(header));
    std::memcpy(bytes + sizeof(header), &payload, sizeof(payload));
    if (::send(tcp_, bytes, sizeof(bytes), MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof(bytes))) fail("TCP send");
  }

  // Reads a response of `command` (header, status and `extra` bytes) and checks its status.
  void expect_status(csp::fci::Command command, csp::fci::Status status, std::size_t extra) {
    uint8_t bytes[sizeof(csp::fci::MessageHeader) + 1 + sizeof(csp::fci::Version)];
    const std::size_t size = sizeof(csp::fci::MessageHeader) + 1 + extra;
    for (std::size_t got = 0; got < size;) {
      wait_readable(tcp_, "response");
      const ssize_t n = ::recv(tcp_, bytes + got, size - got, 0);
      if (n <= 0) fail("TCP receive");
      got += static_cast<std::size_t>(n);
    }
    const uint8_t expected = csp::fci::status_code(command, status, csp::fci::kFr3Version);
    if (bytes[sizeof(csp::fci::MessageHeader)] != expected)
      throw std::runtime_error(std::string("minimal FCI client: ") + csp::fci::command_name(command) + " answered status " +
                               std::to_string(bytes[sizeof(csp::fci::MessageHeader)]) + ", expected " +
                               csp::fci::status_name(status));
  }

  // The next state; the commands go back to where it came from (as libfranka does).
  csp::fci::RobotStatePacket receive_state() {
    csp::fci::RobotStatePacket state;
    socklen_t length = sizeof(robot_udp_);
    wait_readable(udp_, "robot state");
    if (::recvfrom(udp_, &state, sizeof(state), 0, reinterpret_cast<sockaddr*>(&robot_udp_), &length) !=
        static_cast<ssize_t>(sizeof(state)))
      fail("UDP receive");
    return state;
  }

  int tcp_ = -1, udp_ = -1;
  uint16_t udp_port_ = 0;
  uint32_t command_id_ = 0;
  sockaddr_in robot_udp_{};
};

SessionFigures run_minimal_client_session(const char* title, Clock clock, const std::string& address) {
  std::atomic<bool> stop = false;
  std::thread client;
  std::optional<Percentiles> command_to_state_us;
  std::string failure;
  const auto start_client = [&] {
    client = std::thread([&] {
      try {
        command_to_state_us = MinimalClient(address).hold(kMinimalClientCycles);
      } catch (const std::exception& e) {
        failure = e.what();
      }
      stop = true;
    });
  };
  SessionFigures figures;
  figures.name = "FCI, minimal client";
  const double self_cpu = cpu_seconds(RUSAGE_SELF);
  const csp::fci::FciServeReport r = serve_fr3(clock, address, stop, start_client, figures);
  if (client.joinable()) client.join();
  figures.command_to_state_us = command_to_state_us;
  print_fci_session(title, r, figures);
  if (command_to_state_us) print_round_trip("command sent -> next state received (client)", *command_to_state_us);
  if (!failure.empty()) std::printf("  FAILED: %s\n", failure.c_str());
  std::printf("  CPU: server and client (one process) %.3f s\n", cpu_seconds(RUSAGE_SELF) - self_cpu);
  return figures;
}

// --- The table --------------------------------------------------------------------------------

double ratio(double fci, double lcm) { return lcm > 0.0 ? fci / lcm : 0.0; }

void print_table(const char* clock, const std::vector<SessionFigures>& sessions) {
  const SessionFigures& lcm = sessions.front();
  std::printf("\n%s clock | motion cycles | cycles/s (without stalls) | lost | round trip p50 / p99 / p99.9 / max [us] | "
              "command -> next state p50 / p99 / p99.9 [us] | FCI/LCM: cycles/s, p50, p99, p99.9\n",
              clock);
  for (const SessionFigures& s : sessions) {
    std::printf("%s | %llu | %.0f", s.name.c_str(), static_cast<unsigned long long>(s.motion_cycles), s.cycles_per_second());
    if (s.stalls > 0) std::printf(" (%.0f)", s.cycles_per_second_without_stalls());
    std::printf(" | %llu | %.1f / %.1f / %.1f / %.1f | ",
                static_cast<unsigned long long>(s.lost_commands), s.round_trip_us.p50, s.round_trip_us.p99,
                s.round_trip_us.p999, s.round_trip_us.max);
    if (s.command_to_state_us)
      std::printf("%.1f / %.1f / %.1f | ", s.command_to_state_us->p50, s.command_to_state_us->p99, s.command_to_state_us->p999);
    else
      std::printf("- | ");
    if (&s == &lcm)
      std::printf("-\n");
    else
      std::printf("%.2f, %.2f, %.2f, %.2f\n", ratio(s.cycles_per_second(), lcm.cycles_per_second()),
                  ratio(s.round_trip_us.p50, lcm.round_trip_us.p50), ratio(s.round_trip_us.p99, lcm.round_trip_us.p99),
                  ratio(s.round_trip_us.p999, lcm.round_trip_us.p999));
  }
}

void log_write_rate(int count) {
  const std::string path = csp::test::temp_path("bench.lcmlog");
  csp::rt::Emulator emulator(csp::rt::load_scenario(csp::rt::default_scenario_path()).emulator);
  const std::vector<uint8_t> bytes = csp::bridge::encode(csp::bridge::to_message(emulator.state(), 0, false));
  const double cpu = cpu_seconds(RUSAGE_SELF);
  const auto start = std::chrono::steady_clock::now();
  {
    csp::bridge::LogWriter log(path);
    for (int i = 0; i < count; ++i) log.write("CSP_STATE", bytes, i);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double megabytes = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  std::printf("log write: %d state messages (%zu bytes each) in %.3f s (CPU %.3f s) = %.0f messages/s, %.0f MB/s\n", count,
              bytes.size(), seconds, cpu_seconds(RUSAGE_SELF) - cpu, count / seconds, megabytes / seconds);
  std::filesystem::remove(path);
}

// The three sessions on one clock. Each FCI session has a loopback address of its own (the tests
// use 127.0.0.10 to .23).
std::vector<SessionFigures> run_sessions(Clock clock, int lcm_port_offset, int first_host) {
  const std::string clock_name = clock == Clock::kLockstep ? "lockstep" : "real time";
  const std::string host = "127.0.0.";
  std::vector<SessionFigures> sessions;
  sessions.push_back(run_lcm_session((clock_name + ", LCM, csp_lcm_float process").c_str(), clock, kSessionSeconds, lcm_port_offset));
  if (std::optional<SessionFigures> libfranka = run_libfranka_session(
          (clock_name + ", FCI, libfranka 0.13.3 communication_test process").c_str(), clock, host + std::to_string(first_host)))
    sessions.push_back(*libfranka);
  sessions.push_back(run_minimal_client_session((clock_name + ", FCI, minimal client thread").c_str(), clock,
                                                host + std::to_string(first_host + 1)));
  return sessions;
}

}  // namespace

int main() {
  const std::vector<SessionFigures> lockstep = run_sessions(Clock::kLockstep, 4, 200);
  const std::vector<SessionFigures> realtime = run_sessions(Clock::kRealtime, 5, 202);
  print_table("lockstep", lockstep);
  print_table("real time", realtime);
  std::printf("\n");
  log_write_rate(200000);
  return 0;
}
