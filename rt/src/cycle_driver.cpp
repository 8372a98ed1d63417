#include "csp/rt/cycle_driver.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace csp::rt {

const char* clock_name(Clock clock) { return clock == Clock::kLockstep ? "lockstep" : "real-time"; }

RealtimeResources enable_realtime_scheduling() {
  RealtimeResources obtained;
  obtained.memory_locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  if (!obtained.memory_locked) obtained.problems.push_back(std::string("mlockall: ") + std::strerror(errno));
  sched_param param{};
  param.sched_priority = sched_get_priority_max(SCHED_FIFO) - 1;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  obtained.scheduling = error == 0;
  if (!obtained.scheduling) obtained.problems.push_back(std::string("SCHED_FIFO: ") + std::strerror(error));
  return obtained;
}

CycleDriver::CycleDriver(Clock clock, RealtimeConfig config, int64_t (*now_ns)()) : now_ns_(now_ns), start_ns_(now_ns()) {
  report_.clock = clock;
  if (clock == Clock::kLockstep) return;
  report_.realtime = enable_realtime_scheduling();
  const std::vector<std::string>& problems = report_.realtime.problems;
  if (!problems.empty()) {
    std::string text = "no real-time scheduling (" + problems.front();
    for (std::size_t i = 1; i < problems.size(); ++i) text += "; " + problems[i];
    text += ")";
    if (config == RealtimeConfig::kEnforce) throw RealtimeError(text + "; use RealtimeConfig::kIgnore to run anyway");
    report_.warnings.push_back(text + ": running without, timing will suffer");
  }
  clock_.emplace(now_ns_);   // the first deadline one period from now
}

void CycleDriver::wait() {
  if (clock_) clock_->wait();
}

bool CycleDriver::deadline_reached() { return !clock_ || clock_->reached(); }

int64_t CycleDriver::time_to_spin_ns() const { return clock_ ? clock_->time_to_spin_ns() : 0; }

int64_t CycleDriver::end_cycle() { return clock_ ? clock_->end_cycle() : 0; }

void CycleDriver::count_cycle(bool lost_command) {
  ++report_.cycles;
  if (lost_command) ++report_.lost_commands;
}

void CycleDriver::add_round_trip_ns(int64_t ns) { round_trip_us_.add(static_cast<double>(ns) * 1e-3); }

TimingReport CycleDriver::report() const {
  TimingReport report = report_;
  report.round_trip_us = round_trip_us_.percentiles();
  report.wall_seconds = static_cast<double>(now_ns_() - start_ns_) * 1e-9;
  if (clock_) {
    report.overruns = clock_->overruns();
    report.missed_deadlines = clock_->missed_deadlines();
    report.wakeup_latency_us = clock_->wakeup_latency_us().percentiles();
  }
  return report;
}

namespace {

constexpr int64_t kRepeatStateNs = 10'000'000;   // lockstep: repeat a waiting state for late joiners

// Handles messages until `done()` or the monotonic time `deadline_ns`, repeating the state every
// 10 ms if `repeat`. Returns done().
template <typename Done>
bool receive_until(MessageBus& bus, int64_t deadline_ns, bool repeat, const Done& done) {
  int64_t next_repeat = monotonic_ns() + kRepeatStateNs;
  while (!done() && !bus.stopped()) {
    const int64_t now = monotonic_ns();
    if (now >= deadline_ns) return false;
    if (repeat && now >= next_repeat) {
      bus.repeat_state();
      next_repeat = now + kRepeatStateNs;
    }
    bus.receive_for(std::min(deadline_ns, repeat ? next_repeat : deadline_ns) - now);
  }
  return done();
}

double run_realtime(MessageBus& bus, CycleDriver& driver, uint64_t cycles) {
  double session_seconds = 0.0;
  const auto more = [&] { return driver.cycles() < cycles; };
  while (more() && !bus.stopped()) {
    const int64_t cycle_start = monotonic_ns();
    // Messages until the deadline: blocking until the spin point, then polling without blocking,
    // so that the deadline is met as closely as by a sleep and a spin.
    while (!driver.deadline_reached() && !bus.stopped()) bus.receive_for(driver.time_to_spin_ns());
    const bool session_cycle = bus.in_session();
    bus.robot_cycle(driver);
    driver.catch_up(driver.end_cycle(), [&] { bus.robot_cycle(driver); }, more);
    if (session_cycle) session_seconds += static_cast<double>(monotonic_ns() - cycle_start) * 1e-9;
  }
  return session_seconds;
}

double run_lockstep(MessageBus& bus, CycleDriver& driver, const BusPacing& pacing) {
  double session_seconds = 0.0;
  const auto timeout_ns = static_cast<int64_t>(pacing.lockstep_timeout * 1e9);
  const auto session_running = [&] { return bus.in_session(); };
  int64_t deadline = monotonic_ns();
  while (driver.cycles() < pacing.cycles && !bus.stopped()) {
    const int64_t cycle_start = monotonic_ns();
    deadline += DeadlineClock::kPeriodNs;
    if (driver.cycles() == 0 && pacing.wait_for_controller) receive_until(bus, INT64_MAX, true, session_running);
    else if (!bus.in_session()) receive_until(bus, deadline, false, session_running);
    if (bus.in_session()) receive_until(bus, monotonic_ns() + timeout_ns, true, [&] { return bus.answered(); });
    const bool session_cycle = bus.in_session();
    bus.robot_cycle(driver);
    const int64_t now = monotonic_ns();
    if (session_cycle) session_seconds += static_cast<double>(now - cycle_start) * 1e-9;
    // A session's cycles run as fast as the controller answers; idle cycles after it keep the
    // wall-clock pace from its end rather than from the schedule it ran ahead of.
    deadline = session_cycle ? now : std::max(deadline, now);
  }
  return session_seconds;
}

}  // namespace

double run_bus_cycles(MessageBus& bus, CycleDriver& driver, const BusPacing& pacing) {
  if (driver.clock() == Clock::kRealtime) return run_realtime(bus, driver, pacing.cycles);
  return run_lockstep(bus, driver, pacing);
}

}  // namespace csp::rt
