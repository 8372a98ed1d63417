#include "csp/bridge/serve.hpp"

#include <poll.h>
#include <time.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/lcm_url.hpp"

namespace csp::bridge {
namespace {

constexpr int64_t kCycleNs = 1'000'000;
constexpr int64_t kRepublishNs = 10'000'000;   // lockstep: repeat a waiting state for late joiners
constexpr uint64_t kStatusEvery = 100;         // cycles between status messages

int64_t monotonic_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// The LCM side of one serve run: publication (and logging), reception into the RobotServer.
class Bus {
 public:
  Bus(const rt::Scenario& scenario, const ServeOptions& options)
      : options_(options), channels_(options.channel_prefix), lcm_(checked_lcm_url(options.lcm_url)) {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM at `" + options.lcm_url + "`");
    if (!options.log_path.empty()) log_ = std::make_unique<LogWriter>(options.log_path);
    if (log_) log_->write(channels_.scenario, encode(scenario_message(scenario, options.channel_prefix)), now_utime());
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
      const int64_t wait = std::min(deadline_ns, republish ? next_republish : deadline_ns) - now;
      pollfd fd{lcm_.getFileno(), POLLIN, 0};
      const timespec timeout{wait / 1'000'000'000, wait % 1'000'000'000};
      if (ppoll(&fd, 1, &timeout, nullptr) > 0) lcm_.handle();
    }
    return done();
  }

  bool stopped() const { return options_.stop && options_.stop->load(); }
  uint64_t state_messages() const { return state_messages_; }
  std::vector<double>& round_trip_us() { return round_trip_us_; }

 private:
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    // Logged as received, before it is judged: replay judges it again the same way.
    if (log_) log_->write(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    server_->receive(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    if (server_->answered() && !round_trip_recorded_) {
      round_trip_us_.push_back(static_cast<double>(monotonic_ns() - published_ns_) * 1e-3);
      round_trip_recorded_ = true;
    }
  }

  const ServeOptions& options_;
  Channels channels_;
  lcm::LCM lcm_;
  std::unique_ptr<LogWriter> log_;
  std::unique_ptr<RobotServer> server_;
  uint64_t state_messages_ = 0;
  int64_t published_ns_ = 0;
  bool round_trip_recorded_ = false;
  std::vector<double> round_trip_us_;
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
  const auto timeout_ns = static_cast<int64_t>(options.lockstep_timeout * 1e9);
  bus.round_trip_us().reserve(cycles);
  const int64_t start_ns = monotonic_ns();
  int64_t deadline = start_ns;

  while (report.cycles < cycles && !bus.stopped()) {
    const int64_t cycle_start = monotonic_ns();
    bus.publish_state(false);
    deadline += kCycleNs;
    if (options.clock == rt::Clock::kRealtime) {
      // Commands count only if they arrive before the next deadline (the FCI's rule).
      bus.pump_until(deadline, false, [] { return false; });
    } else {
      // Lockstep: idle cycles pass at the wall-clock pace (a controller may start a session);
      // a session's cycle waits for its command up to the timeout.
      const auto session_running = [&] { return server.in_session(); };
      if (report.cycles == 0 && options.wait_for_controller) bus.pump_until(INT64_MAX, true, session_running);
      else if (!server.in_session()) bus.pump_until(deadline, false, session_running);
      if (server.in_session()) bus.pump_until(monotonic_ns() + timeout_ns, true, [&] { return server.answered(); });
    }
    const bool session_cycle = server.in_session();
    server.step(now_utime());
    ++report.cycles;
    const int64_t now = monotonic_ns();
    if (session_cycle) report.motion_wall_seconds += static_cast<double>(now - cycle_start) * 1e-9;
    if (options.clock == rt::Clock::kRealtime && now > deadline + kCycleNs) {
      ++report.overruns;
      deadline = now;   // late: the next cycle starts now instead of catching up
    } else if (options.clock == rt::Clock::kLockstep) {
      // A session's cycles run as fast as the controller answers; idle cycles after it keep the
      // wall-clock pace from its end rather than from the schedule it ran ahead of.
      deadline = session_cycle ? now : std::max(deadline, now);
    }
    if (report.cycles % kStatusEvery == 0)
      bus.publish(bus.channels().status, encode(status_message(server, report, rt::percentiles(bus.round_trip_us()))));
  }
  bus.publish_state(false);   // the state the last cycle produced

  report.counters = server.counters();
  report.emulator = server.emulator().counters();
  report.round_trip_us = rt::percentiles(bus.round_trip_us());
  report.wall_seconds = static_cast<double>(monotonic_ns() - start_ns) * 1e-9;
  report.last_reflex = server.emulator().reflex_reason();
  bus.publish(bus.channels().status, encode(status_message(server, report, report.round_trip_us)));
  report.state_messages = bus.state_messages();
  if (bus.log()) {
    bus.log()->flush();
    report.log_events = bus.log()->events();
  }
  return report;
}

}  // namespace csp::bridge
