#include "csp/bridge/serve.hpp"

#include <poll.h>
#include <time.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/lcm_url.hpp"
#include "csp/rt/cycle_driver.hpp"

namespace csp::bridge {
namespace {

using rt::monotonic_ns;

constexpr uint64_t kStatusEvery = 100;         // cycles between status messages
// Cycles between republications of the scenario record (about 16 kB: the scenario and robot files),
// so that a recording begun after the start (lcm-logger) holds it: once a second of robot time.
constexpr uint64_t kScenarioEvery = 1000;

// The LCM side of one serve run: publication (and logging), reception into the RobotServer.
class Bus : public rt::MessageBus {
 public:
  Bus(rt::Emulator& robot, const rt::Scenario& scenario, const ServeOptions& options)
      : options_(options),
        channels_(options.channel_prefix),
        lcm_(checked_lcm_url(options.lcm_url)),
        scenario_record_(encode(scenario_message(scenario, options.channel_prefix))) {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM at `" + options.lcm_url + "`");
    if (!options.log_path.empty()) log_ = std::make_unique<LogWriter>(options.log_path);
    publish_scenario();   // the first event of the log
    server_ = std::make_unique<RobotServer>(
        robot, channels_, [this](const std::string& channel, const std::vector<uint8_t>& bytes) { publish(channel, bytes); },
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
    // state is still being logged. It is timed for states published in a control session: not
    // the wait for a controller to start one.
    if (!repeat) {
      published_ns_ = monotonic_ns();
      answered_ns_.reset();
      timed_ = server_->in_session();
    }
    lcm_.publish(channels_.state, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (repeat) return;
    if (log_) log_->write(channels_.state, bytes, utime);
    ++state_messages_;
  }

  // Handles the messages that arrive within `wait_ns` (0: only those already there).
  void receive_for(int64_t wait_ns) override {
    pollfd fd{lcm_.getFileno(), POLLIN, 0};
    const timespec timeout{wait_ns / 1'000'000'000, wait_ns % 1'000'000'000};
    if (ppoll(&fd, 1, &timeout, nullptr) > 0) lcm_.handle();
  }

  bool stopped() const override { return options_.stop && options_.stop->load(); }
  bool in_session() const override { return server_->in_session(); }
  bool answered() const override { return server_->answered(); }
  void repeat_state() override { publish_state(true); }
  void robot_cycle(rt::CycleDriver& driver) override;
  uint64_t state_messages() const { return state_messages_; }
  // Publication of the state -> its command received, for a state of a control session.
  std::optional<int64_t> round_trip_ns() const {
    if (!timed_ || !answered_ns_) return std::nullopt;
    return *answered_ns_ - published_ns_;
  }

 private:
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    // Logged as received, before it is judged: replay judges it again the same way.
    if (log_) log_->write(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    server_->receive(channel, buffer->data, static_cast<int>(buffer->data_size), buffer->recv_utime);
    if (server_->answered() && !answered_ns_) answered_ns_ = monotonic_ns();
  }

  const ServeOptions& options_;
  Channels channels_;
  lcm::LCM lcm_;
  std::vector<uint8_t> scenario_record_;
  std::unique_ptr<LogWriter> log_;
  std::unique_ptr<RobotServer> server_;
  uint64_t state_messages_ = 0;
  int64_t published_ns_ = 0;
  bool timed_ = false;
  std::optional<int64_t> answered_ns_;
};

status_t status_message(const RobotServer& server, const rt::TimingReport& timing) {
  const ServerCounters& c = server.counters();
  const rt::EmulatorCounters& e = server.emulator().counters();
  status_t s;
  s.utime = now_utime();
  s.cycles = static_cast<int64_t>(timing.cycles);
  s.sessions = static_cast<int64_t>(c.sessions);
  s.motion_cycles = static_cast<int64_t>(e.motion_cycles);
  s.lost_commands = static_cast<int64_t>(e.lost_commands);
  s.max_consecutive_lost = e.max_consecutive_lost;
  s.reflexes = static_cast<int64_t>(e.reflexes);
  s.overruns = static_cast<int64_t>(timing.overruns);
  s.rejected_fingerprint = static_cast<int64_t>(c.rejected_fingerprint);
  s.rejected_truncated = static_cast<int64_t>(c.rejected_truncated);
  s.rejected_oversized = static_cast<int64_t>(c.rejected_oversized);
  s.rejected_stale = static_cast<int64_t>(c.rejected_stale);
  s.rejected_wrong_mode = static_cast<int64_t>(c.rejected_wrong_mode);
  s.rejected_no_session = static_cast<int64_t>(c.rejected_no_session);
  s.non_finite_commands = static_cast<int64_t>(c.non_finite_commands);
  s.round_trip_p50_us = timing.round_trip_us.p50;
  s.round_trip_p99_us = timing.round_trip_us.p99;
  s.round_trip_max_us = timing.round_trip_us.max;
  s.last_reflex = server.emulator().reflex_reason();
  return s;
}

// One robot cycle of a serve run: the server steps with the command that answered the state (or
// none), the new state is published; the status every kStatusEvery cycles, the scenario record
// every kScenarioEvery.
void Bus::robot_cycle(rt::CycleDriver& driver) {
  RobotServer& server = *server_;
  const bool lost = server.in_session() && !server.answered();
  if (const std::optional<int64_t> round_trip = round_trip_ns()) driver.add_round_trip_ns(*round_trip);
  server.step(now_utime());
  driver.count_cycle(lost);
  publish_state(false);
  const uint64_t cycles = driver.cycles();
  if (cycles % kStatusEvery == 0) publish(channels_.status, encode(status_message(server, driver.report())));
  if (cycles % kScenarioEvery == 0) publish_scenario();
  if (options_.after_cycle) options_.after_cycle(server.emulator().state(), server.last_cycle());
}

}  // namespace

ServeReport serve(rt::Emulator& robot, const rt::Scenario& scenario, const ServeOptions& options) {
  if (!(options.duration > 0.0) || !std::isfinite(options.duration)) throw std::invalid_argument("duration: expected a positive number of seconds");
  if (!(options.lockstep_timeout > 0.0 && options.lockstep_timeout <= 3600.0))
    throw std::invalid_argument("lockstep timeout: expected a positive number of seconds, at most 3600");
  Bus bus(robot, scenario, options);
  RobotServer& server = bus.server();
  ServeReport report;
  rt::CycleDriver driver(options.clock);
  rt::BusPacing pacing;
  pacing.cycles = static_cast<uint64_t>(std::llround(options.duration / rt::kDeltaT));
  pacing.lockstep_timeout = options.lockstep_timeout;
  pacing.wait_for_controller = options.wait_for_controller;
  bus.publish_state(false);
  report.motion_wall_seconds = rt::run_bus_cycles(bus, driver, pacing);

  report.timing = driver.report();
  report.counters = server.counters();
  report.emulator = server.emulator().counters();
  report.last_reflex = server.emulator().reflex_reason();
  bus.publish(bus.channels().status, encode(status_message(server, report.timing)));
  bus.publish_scenario();
  report.state_messages = bus.state_messages();
  if (bus.log()) {
    bus.log()->flush();
    report.log_events = bus.log()->events();
  }
  return report;
}

}  // namespace csp::bridge
