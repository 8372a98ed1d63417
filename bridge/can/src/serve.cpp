#include "csp/can/serve.hpp"

#include <cctype>
#include <cmath>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "csp/rt/cycle_driver.hpp"

namespace csp::can {
namespace {

using rt::monotonic_ns;

// Sync clock with CSP's SYNC: how long a cycle waits for the enabled joints' RPDOs before it
// runs without them (lost), and the pace while no joint is enabled.
constexpr int64_t kLockstepTimeoutNs = 100'000'000;
constexpr int64_t kIdleSyncNs = 1'000'000;
constexpr int64_t kIdleAfterNs = 100'000'000;

// One serve run: the sockets, the drives, the robot, the bus-load counters.
class CanSession {
 public:
  CanSession(rt::Emulator& robot, const rt::Scenario& scenario, const CanServeOptions& options, rt::CycleDriver& driver)
      : options_(options),
        driver_(driver),
        arm_(robot, scenario, options.log_path,
             [this](const std::string& line) {
               if (!options_.quiet) std::cerr << "csp can serve: " << line << '\n';
             }),
        bus_(BusSettings{}, arm_) {
    const std::vector<std::string> names = split_interfaces(options.interface, options.split);
    for (std::size_t i = 0; i < names.size(); ++i) {
      sockets_.push_back(std::make_unique<SocketCan>(names[i]));
      socket_list_.push_back(sockets_.back().get());
      report_.interfaces.push_back(InterfaceReport{names[i], {}, {}, {}, 0.0});
    }
    for (int j = 0; j < kJoints; ++j) {
      report_.interfaces[interface_of_joint(j, options.split)].joints.push_back(j + 1);
      interface_of_node_[BusSettings{}.node_ids[j]] = interface_of_joint(j, options.split);
    }
    sync_pending_.assign(names.size(), false);
    flush();   // the boot-up messages
  }

  DriveBus& bus() { return bus_; }
  ServerArm& arm() { return arm_; }
  CanServeReport& report() { return report_; }
  void collect_socket_counters() {
    for (std::size_t i = 0; i < sockets_.size(); ++i) report_.interfaces[i].socket = sockets_[i]->counters();
  }
  uint64_t syncs_marked() const { return syncs_marked_; }
  bool stopped() const { return options_.stop && options_.stop->load(); }

  // Handles the frames waiting on every interface. A SYNC runs the cycle once it has come on
  // every interface; an interface's frames after its SYNC wait for that cycle.
  void receive() {
    for (std::size_t i = 0; i < sockets_.size(); ++i) {
      while (!sync_pending_[i]) {
        const std::optional<Frame> frame = sockets_[i]->receive();
        if (!frame) break;
        report_.interfaces[i].load.add(*frame);
        if (frame->id == kSync) on_sync(i, *frame);
        else bus_.receive(*frame);
      }
    }
    time_round_trip();
    flush();
  }

  // CSP's SYNC on every interface.
  void produce_sync() {
    Frame sync;
    sync.id = kSync;
    mark_sync();
    for (std::size_t i = 0; i < sockets_.size(); ++i) send(i, sync);
    robot_cycle([&] { bus_.receive(sync); });
  }

  void cycle_without_sync() {
    robot_cycle([&] { bus_.cycle_without_sync(); });
  }

  // Waits up to `timeout_ns` for frames.
  void wait(int64_t timeout_ns) {
    bool all_pending = true;
    for (bool p : sync_pending_) all_pending = all_pending && p;
    if (!all_pending) wait_readable(socket_list_, timeout_ns);
  }

  // Sync clock: heartbeat time is robot time (1 ms per cycle) while cycles run, and wall time
  // while none has run for kIdleAfterNs (a master that has not started, or has stopped, SYNC).
  void elapse() {
    const int64_t now = monotonic_ns();
    const int64_t us = (now - last_elapse_ns_) / 1000;
    if (us <= 0) return;
    last_elapse_ns_ += us * 1000;
    if (now - last_cycle_ns_ < kIdleAfterNs) return;
    bus_.elapse(static_cast<uint32_t>(std::min<int64_t>(us, 1'000'000)));
    flush();
  }

  // Sync clock with CSP's SYNC: every enabled joint's RPDO has come (or none is enabled and a
  // millisecond passed, or the enabled ones waited too long).
  bool sync_due(int64_t since_last_sync_ns) const {
    const EnabledJoints joints = enabled_joints();
    if (joints.enabled == 0) return since_last_sync_ns >= kIdleSyncNs;
    return joints.received == joints.enabled || since_last_sync_ns >= kLockstepTimeoutNs;
  }

 private:
  // The joints in operation enabled, and how many of them have this cycle's RPDO.
  struct EnabledJoints {
    int enabled = 0, received = 0;
  };
  EnabledJoints enabled_joints() const {
    EnabledJoints joints;
    for (int j = 0; j < kJoints; ++j) {
      const JointCommand c = bus_.node(j).command();
      joints.enabled += c.operation_enabled ? 1 : 0;
      joints.received += c.operation_enabled && c.received ? 1 : 0;
    }
    return joints;
  }

  // One robot cycle (`run`: the bus's SYNC, or a cycle without one), counted by the driver: its
  // command is lost unless every enabled joint's RPDO came. The state's TPDOs go out at the SYNC:
  // the round trip of a session's cycle runs from here to the last enabled joint's RPDO. The run's
  // observers see the cycle once its frames are sent.
  template <typename Run>
  void robot_cycle(const Run& run) {
    const uint64_t lost_before = bus_.counters().lost_cycles;
    run();
    driver_.count_cycle(bus_.counters().lost_cycles != lost_before);
    last_cycle_ns_ = monotonic_ns();
    answered_ = false;
    timed_ = arm_.server().in_session();
    if (options_.clock == rt::Clock::kLockstep) bus_.elapse(1000);
    flush();
    const bridge::RobotServer& server = arm_.server();
    if (options_.after_cycle) options_.after_cycle(server.emulator().state(), server.last_cycle());
  }

  void time_round_trip() {
    if (!timed_ || answered_) return;
    const EnabledJoints joints = enabled_joints();
    if (joints.enabled == 0 || joints.received < joints.enabled) return;
    answered_ = true;
    driver_.add_round_trip_ns(monotonic_ns() - last_cycle_ns_);
  }

  void on_sync(std::size_t interface, const Frame& sync) {
    sync_pending_[interface] = true;
    for (bool p : sync_pending_)
      if (!p) return;
    sync_pending_.assign(sync_pending_.size(), false);
    mark_sync();
    robot_cycle([&] { bus_.receive(sync); });
  }

  // The bus load at 1 kHz counts the traffic between the first and the last SYNC.
  void mark_sync() {
    for (InterfaceReport& i : report_.interfaces) {
      if (syncs_marked_ == 0) i.bits_at_first_sync = i.load.bits();
      i.bits_at_last_sync = i.load.bits();
    }
    ++syncs_marked_;
  }

  void send(std::size_t interface, const Frame& frame) {
    report_.interfaces[interface].load.add(frame);
    sockets_[interface]->send(frame);
  }

  // The nodes' frames, each to its node's interface.
  void flush() {
    for (const Frame& f : bus_.sent()) send(static_cast<std::size_t>(interface_of_node_[f.id & 0x7F]), f);
    bus_.clear_sent();
  }

  const CanServeOptions& options_;
  rt::CycleDriver& driver_;
  ServerArm arm_;
  DriveBus bus_;
  std::vector<std::unique_ptr<SocketCan>> sockets_;
  std::vector<SocketCan*> socket_list_;
  std::array<int, 128> interface_of_node_{};
  std::vector<bool> sync_pending_;
  int64_t last_elapse_ns_ = monotonic_ns();
  int64_t last_cycle_ns_ = 0;
  bool timed_ = false;      // the cycle last run was one of a control session
  bool answered_ = false;   // and every enabled joint's RPDO has come since
  CanServeReport report_;
  uint64_t syncs_marked_ = 0;
};

void run_sync(CanSession& s, const rt::CycleDriver& driver, uint64_t cycles, const CanServeOptions& options) {
  int64_t last_sync = monotonic_ns();
  while (driver.cycles() < cycles && !s.stopped()) {
    if (options.sync_producer) {
      s.wait(std::min<int64_t>(kIdleSyncNs, 10'000'000));
      s.receive();
      const int64_t now = monotonic_ns();
      if (s.sync_due(now - last_sync)) {
        s.produce_sync();
        last_sync = now;
      }
    } else {
      s.wait(10'000'000);   // heartbeats keep their pace while the master is silent
      s.receive();
    }
    s.elapse();
  }
}

// Real time: frames until the deadline; at it CSP's SYNC (sync_producer), or a cycle without a
// command if the master's SYNC did not come; a late cycle is caught up (rt::CycleDriver).
void run_realtime(CanSession& s, rt::CycleDriver& driver, uint64_t cycles, const CanServeOptions& options) {
  const auto more = [&] { return driver.cycles() < cycles; };
  while (more() && !s.stopped()) {
    const uint64_t cycles_before = driver.cycles();
    while (!driver.deadline_reached() && !s.stopped()) {
      s.wait(driver.time_to_spin_ns());
      s.receive();
    }
    s.bus().elapse(static_cast<uint32_t>(rt::DeadlineClock::kPeriodNs / 1000));
    const auto robot_cycle = [&] {
      if (options.sync_producer) s.produce_sync();
      else s.cycle_without_sync();
    };
    if (options.sync_producer || driver.cycles() == cycles_before) robot_cycle();
    driver.catch_up(driver.end_cycle(), robot_cycle, more);
  }
}

}  // namespace

std::vector<std::string> split_interfaces(const std::string& first, int split) {
  if (split < 1 || split > kJoints) throw std::invalid_argument("--split: expected 1 to 7 interfaces");
  if (split == 1) return {first};
  std::size_t digits = first.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(first[digits - 1]))) --digits;
  if (digits == first.size() || first.size() - digits > 3)
    throw std::invalid_argument("--split: the interface `" + first + "` must end in a number (vcan0: vcan0, vcan1, ...)");
  const int base = std::stoi(first.substr(digits));
  std::vector<std::string> names;
  for (int i = 0; i < split; ++i) names.push_back(first.substr(0, digits) + std::to_string(base + i));
  return names;
}

int interface_of_joint(int joint, int split) { return joint * split / kJoints; }

CanServeReport serve(rt::Emulator& robot, const rt::Scenario& scenario, const CanServeOptions& options) {
  if (!(options.duration > 0.0) || !std::isfinite(options.duration)) throw std::invalid_argument("duration: expected a positive number of seconds");
  if (!(options.bitrate >= 1e3 && options.bitrate <= 1e7)) throw std::invalid_argument("--bitrate: expected 1000 to 10000000 bit/s");
  rt::CycleDriver driver(options.clock);
  CanSession session(robot, scenario, options, driver);
  CanServeReport& report = session.report();
  const auto cycles = static_cast<uint64_t>(std::llround(options.duration / rt::kDeltaT));
  if (options.clock == rt::Clock::kRealtime) run_realtime(session, driver, cycles, options);
  else run_sync(session, driver, cycles, options);

  report.timing = driver.report();
  session.collect_socket_counters();
  report.bus = session.bus().counters();
  report.arm = session.arm().counters();
  report.server = session.arm().server().counters();
  report.emulator = session.arm().server().emulator().counters();
  report.last_reflex = session.arm().server().emulator().reflex_reason();
  for (const InterfaceReport& i : report.interfaces) {
    const SocketCounters& c = i.socket;
    if (c.dropped > 0)
      report.timing.warnings.push_back(i.name + ": " + std::to_string(c.dropped) +
                                       " frames dropped: the socket's receive queue was full (the kernel's SO_RXQ_OVFL count); the drives never saw them");
    // The session log says what reached the drives, for every interface.
    session.arm().log_event("can: " + i.name + ": received " + std::to_string(c.received) + " frames, dropped " +
                            std::to_string(c.dropped) + " (receive queue full), late " + std::to_string(c.late) +
                            " (handled more than 1 ms after they came), sent " + std::to_string(c.sent));
  }
  for (InterfaceReport& i : report.interfaces) {
    if (session.syncs_marked() < 2) continue;
    const double seconds = static_cast<double>(session.syncs_marked() - 1) * rt::kDeltaT;
    i.load_percent = 100.0 * static_cast<double>(i.bits_at_last_sync - i.bits_at_first_sync) / (options.bitrate * seconds);
    if (i.load_percent > 100.0)
      report.timing.warnings.push_back(i.name + ": the traffic needs " + std::to_string(static_cast<int>(std::lround(i.load_percent))) +
                                " % of a " + std::to_string(static_cast<int64_t>(options.bitrate)) +
                                " bit/s bus at 1 kHz: it would not fit on a real bus (use --split)");
  }
  if (session.arm().log()) {
    session.arm().log()->flush();
    report.log_events = session.arm().log()->events();
  }
  return report;
}

}  // namespace csp::can
