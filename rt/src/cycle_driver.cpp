#include "csp/rt/cycle_driver.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

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

}  // namespace csp::rt
