#include "csp/bridge/serve.hpp"

#include <poll.h>
#include <time.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/lcm_url.hpp"
#include "csp/rt/deadline_clock.hpp"

namespace csp::bridge {
namespace {

using rt::monotonic_ns;

constexpr int64_t kCycleNs = rt::DeadlineClock::kPeriodNs;
constexpr int64_t kRepublishNs = 10'000'000;   // lockstep: repeat a waiting state for late joiners
constexpr uint64_t kStatusEvery = 100;         // cycles between status messages
// Cycles between republications of the scenario record (about 16 kB: the scenario and robot files),
// so that a recording begun after the start (lcm-logger) holds it: once a second of robot time.
constexpr uint64_t kScenarioEvery = 1000;

// The LCM side of one serve run: publication (and logging), reception into the RobotServer.
class Bus {
 public:
  Bus(const rt::Scenario& scenario, const ServeOptions& options)
      : options_(options),
        channels_(options.channel_prefix),
        lcm_(checked_lcm_url(options.lcm_url)),
        scenario_record_(encode(scenario_message(scenario, options.channel_prefix))) {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM at `" + options.lcm_url + "`");
    if (!options.log_path.empty()) log_ = std::make_unique<LogWriter>(options.log_path);
    publish_scenario();   // the first event of the log
    server_ = std::make_unique<RobotServer>(
        scenario.emulator, channels_, [this](const std::string& channel, const std::vector<uint8_t>& bytes) { publish(channel, bytes); },
        [this](const std::string& line) {
          if (!options_.quiet) std::cerr << "csp serve: " << line << '\n';
        });
    // Function-pointer subscriptions: GCC 12's UBSan misreports LCM's member-function-pointer call.
    const auto on_message = +[](const lcm::ReceiveBuffer* buffer, const std::string& channel, Bus* bus) {
      bus->on_message(buffer, channel);
    };
    lcm_.subscribeFunction(channels_.command, on_message, this);
    lcm_.subscribeFunction(channels_.config, on_message, this);
  }

  RobotServer& server() { return *server_; }
  void publish_scenario() { publish(channels_.scenario, scenario_record_); }
  LogWriter* log() { return log_.get(); }
  const Channels& channels() const { return channels_; }

  void publish(const std::string& channel, const std::vector<uint8_t>& bytes) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (log_) log_->write(channel, bytes, now_utime());
  }

  // Publishes the current state (logged unless it repeats one already published).
  void publish_state(bool repeat) {
    const int64_t utime = now_utime();
    const std::vector<uint8_t> bytes = encode(server_->state_message(utime));
    // The round trip starts before the publication: a fast controller may answer while the
    // state is still being logged.
    if (!repeat) {
      published_ns_ = monotonic_ns();
      round_trip_recorded_ = false;
    }
    lcm_.publish(channels_.state, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (repeat) return;
    if (log_) log_->write(channels_.state, bytes, utime);
    ++state_messages_;
  }

  // Handles messages until `done()` or the monotonic time `deadline_ns`; in lockstep the waiting
  // state is repeated every 10 ms. Returns done().
  template <typename Done>
  bool pump_until(int64_t deadline_ns, bool republish, const Done& done) {
    int64_t next_republish = monotonic_ns() + kRepublishNs;
    while (!done() && !stopped()) {
      const int64_t now = monotonic_ns();
      if (now >= deadline_ns) return false;
      if (republish && now >= next_republish) {
        publish_state(true);
        next_republish = now + kRepublishNs;
      }
      receive_for(std::min(deadline_ns, republish ? next_republish : deadline_ns) - now);
    }
    return done();
  }

  // Real time: handles messages until the clock's deadline, blocking until its spin point and
  // then polling without blocking, so that the deadline is met as closely as by clock.wait().
  void receive_until(rt::DeadlineClock& clock) {
    while (!clock.reached() && !stopped()) receive_for(clock.time_to_spin_ns());
  }

  bool stopped() const { return options_.stop && options_.stop->load(); }
  uint64_t state_messages() const { return state_messages_; }
  const rt::DurationHistogram& round_trip_us() const { return round_trip_us_; }

 private:
  // Handles the messages that arrive within `wait_ns` (0: only those already there).
  void receive_for(int64_t wait_ns) {
    pollfd fd{lcm_.getFileno(), POLLIN, 0};
    const timespec timeout{wait_ns / 1'000'000'000, wait_ns % 1'000'000'000};
    if (ppoll(&fd, 1, &timeout, nullptr) > 0) lcm_.handle();
  }

  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    // Logged as received, before it is judged: replay judges it again the same way.
    if (log_) log_->write(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    server_->receive(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    if (server_->answered() && !round_trip_recorded_) {
      round_trip_us_.add(static_cast<double>(monotonic_ns() - published_ns_) * 1e-3);
      round_trip_recorded_ = true;
    }
  }

  const ServeOptions& options_;
  Channels channels_;
  lcm::LCM lcm_;
  std::vector<uint8_t> scenario_record_;
  std::unique_ptr<LogWriter> log_;
  std::unique_ptr<RobotServer> server_;
  uint64_t state_messages_ = 0;
  int64_t published_ns_ = 0;
  bool round_trip_recorded_ = false;
  rt::DurationHistogram round_trip_us_;
};

status_t status_message(const RobotServer& server, const ServeReport& report, const rt::Percentiles& round_trip) {
  const ServerCounters& c = server.counters();
  const rt::EmulatorCounters& e = server.emulator().counters();
  status_t s;
  s.utime = now_utime();
  s.cycles = static_cast<int64_t>(report.cycles);
  s.sessions = static_cast<int64_t>(c.sessions);
  s.motion_cycles = static_cast<int64_t>(e.motion_cycles);
  s.lost_commands = static_cast<int64_t>(e.lost_commands);
  s.max_consecutive_lost = e.max_consecutive_lost;
  s.reflexes = static_cast<int64_t>(e.reflexes);
  s.overruns = static_cast<int64_t>(report.overruns);
  s.rejected_fingerprint = static_cast<int64_t>(c.rejected_fingerprint);
  s.rejected_truncated = static_cast<int64_t>(c.rejected_truncated);
  s.rejected_oversized = static_cast<int64_t>(c.rejected_oversized);
  s.rejected_stale = static_cast<int64_t>(c.rejected_stale);
  s.rejected_wrong_mode = static_cast<int64_t>(c.rejected_wrong_mode);
  s.rejected_no_session = static_cast<int64_t>(c.rejected_no_session);
  s.non_finite_commands = static_cast<int64_t>(c.non_finite_commands);
  s.round_trip_p50_us = round_trip.p50;
  s.round_trip_p99_us = round_trip.p99;
  s.round_trip_max_us = round_trip.max;
  s.last_reflex = server.emulator().reflex_reason();
  return s;
}

// Status every kStatusEvery cycles, the scenario record every kScenarioEvery.
void publish_periodic_status(Bus& bus, const ServeReport& report) {
  if (report.cycles % kStatusEvery == 0)
    bus.publish(bus.channels().status, encode(status_message(bus.server(), report, bus.round_trip_us().percentiles())));
  if (report.cycles % kScenarioEvery == 0) bus.publish_scenario();
}

// Real time on the DeadlineClock: at each deadline the robot steps with the command received
// since the last state (the FCI's rule: in time only if before this deadline) and publishes the
// new state. A cycle whose step and publication pass the next deadline misses it: the robot runs
// the missed cycles at once, without a command, so that its time keeps pace with the clock's.
void run_realtime(Bus& bus, uint64_t cycles, ServeReport& report) {
  RobotServer& server = bus.server();
  rt::DeadlineClock clock;
  const auto robot_cycle = [&] {
    server.step(now_utime());
    ++report.cycles;
    bus.publish_state(false);
    report.overruns = clock.overruns();
    report.missed_deadlines = clock.missed_deadlines();
    publish_periodic_status(bus, report);
  };
  bus.publish_state(false);
  while (report.cycles < cycles && !bus.stopped()) {
    const int64_t cycle_start = monotonic_ns();
    bus.receive_until(clock);
    const bool session_cycle = server.in_session();
    robot_cycle();
    for (int64_t missed = clock.end_cycle(); missed > 0 && report.cycles < cycles; --missed) robot_cycle();
    if (session_cycle) report.motion_wall_seconds += static_cast<double>(monotonic_ns() - cycle_start) * 1e-9;
  }
  report.overruns = clock.overruns();
  report.missed_deadlines = clock.missed_deadlines();
  report.wakeup_latency_us = clock.wakeup_latency_us().percentiles();
}

// Lockstep: idle cycles pass at the wall-clock pace (a controller may start a session); a
// session's cycle waits for its command up to the timeout.
void run_lockstep(Bus& bus, uint64_t cycles, const ServeOptions& options, ServeReport& report) {
  RobotServer& server = bus.server();
  const auto timeout_ns = static_cast<int64_t>(options.lockstep_timeout * 1e9);
  const auto session_running = [&] { return server.in_session(); };
  int64_t deadline = monotonic_ns();
  while (report.cycles < cycles && !bus.stopped()) {
    const int64_t cycle_start = monotonic_ns();
    bus.publish_state(false);
    deadline += kCycleNs;
    if (report.cycles == 0 && options.wait_for_controller) bus.pump_until(INT64_MAX, true, session_running);
    else if (!server.in_session()) bus.pump_until(deadline, false, session_running);
    if (server.in_session()) bus.pump_until(monotonic_ns() + timeout_ns, true, [&] { return server.answered(); });
    const bool session_cycle = server.in_session();
    server.step(now_utime());
    ++report.cycles;
    const int64_t now = monotonic_ns();
    if (session_cycle) report.motion_wall_seconds += static_cast<double>(now - cycle_start) * 1e-9;
    // A session's cycles run as fast as the controller answers; idle cycles after it keep the
    // wall-clock pace from its end rather than from the schedule it ran ahead of.
    deadline = session_cycle ? now : std::max(deadline, now);
    publish_periodic_status(bus, report);
  }
  bus.publish_state(false);   // the state the last cycle produced
}

}  // namespace

ServeReport serve(const rt::Scenario& scenario, const ServeOptions& options) {
  if (!(options.duration > 0.0) || !std::isfinite(options.duration)) throw std::invalid_argument("duration: expected a positive number of seconds");
  if (!(options.lockstep_timeout > 0.0 && options.lockstep_timeout <= 3600.0))
    throw std::invalid_argument("lockstep timeout: expected a positive number of seconds, at most 3600");
  Bus bus(scenario, options);
  RobotServer& server = bus.server();
  ServeReport report;
  if (options.clock == rt::Clock::kRealtime) {
    for (const std::string& missing : rt::enable_realtime_scheduling())
      report.warnings.push_back("no real-time scheduling (" + missing + "): timing will suffer");
  }
  const auto cycles = static_cast<uint64_t>(std::llround(options.duration / rt::kDeltaT));
  const int64_t start_ns = monotonic_ns();
  if (options.clock == rt::Clock::kRealtime) run_realtime(bus, cycles, report);
  else run_lockstep(bus, cycles, options, report);

  report.counters = server.counters();
  report.emulator = server.emulator().counters();
  report.round_trip_us = bus.round_trip_us().percentiles();
  report.wall_seconds = static_cast<double>(monotonic_ns() - start_ns) * 1e-9;
  report.last_reflex = server.emulator().reflex_reason();
  bus.publish(bus.channels().status, encode(status_message(server, report, report.round_trip_us)));
  bus.publish_scenario();
  report.state_messages = bus.state_messages();
  if (bus.log()) {
    bus.log()->flush();
    report.log_events = bus.log()->events();
  }
  return report;
}

}  // namespace csp::bridge
