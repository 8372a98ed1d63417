#include "csp/rt/control_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>

namespace csp::rt {
namespace {

constexpr int64_t kCycleNs = 1'000'000;

int64_t monotonic_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// Sleeps until shortly before the deadline, then spins to it: waking from a sleep costs tens of
// microseconds on a kernel without PREEMPT_RT, the last stretch of a 1 ms cycle should not.
constexpr int64_t kSpinNs = 100'000;

void sleep_until_ns(int64_t deadline) {
  const int64_t wake = deadline - kSpinNs;
  timespec t{};
  t.tv_sec = wake / 1'000'000'000;
  t.tv_nsec = wake % 1'000'000'000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
  while (monotonic_ns() < deadline) {
  }
}

// One motion's bookkeeping shared by both clocks.
class MotionRunner {
 public:
  MotionRunner(Emulator& emulator, const Controller& controller, const LoopOptions& options)
      : emulator_(emulator), controller_(controller), options_(options), channel_(options.faults) {}

  // Calls the controller for the current state; on an exception the motion is aborted, the cycle
  // reported, and the exception rethrown.
  Command call_controller(Duration period) {
    const int64_t start = monotonic_ns();
    try {
      Command command = controller_(emulator_.state(), period);
      compute_us_.push_back(static_cast<double>(monotonic_ns() - start) * 1e-3);
      return command;
    } catch (const std::exception& e) {
      fail("the controller threw: " + std::string(e.what()));
    } catch (...) {
      fail("the controller threw a non-standard exception");
    }
  }

  // One cycle with the command that was sent (or none) and whether it arrived.
  void step(const std::optional<Command>& sent, bool arrived) {
    CycleInfo info;
    info.command_sent = sent.has_value();
    info.command_received = sent && arrived;
    if (sent) info.command = *sent;
    if (!info.command_received && emulator_.in_motion()) ++report_.lost_commands;
    emulator_.step(info.command_received ? &info.command : nullptr);
    ++report_.cycles;
    if (options_.observer) options_.observer(emulator_.state(), info);
  }

  bool network_delivers() { return channel_.delivers(report_.cycles); }

  // Reflex, or motion_finished was received.
  bool done() const { return !emulator_.in_motion(); }

  // The controller's command of the last cycle of max_duration closes the motion, as if it had
  // returned MotionFinished (a motion generator continues smoothly into it).
  void close_at_max_duration(Command& command) const {
    if (options_.max_duration && static_cast<double>(report_.cycles + 1) * kDeltaT >= *options_.max_duration - 1e-9)
      command.motion_finished = true;
  }

  MotionResult finish() {
    MotionResult result;
    result.reflex = emulator_.state().robot_mode == RobotMode::kReflex;
    result.errors = emulator_.state().last_motion_errors;
    result.reason = emulator_.reflex_reason();
    report_.controller_compute_us = percentiles(compute_us_);
    report_.wakeup_latency_us = percentiles(latency_us_);
    result.timing = report_;
    return result;
  }

  TimingReport& report() { return report_; }
  std::vector<double>& latency_us() { return latency_us_; }

 private:
  [[noreturn]] void fail(const std::string& reason) {
    const std::exception_ptr error = std::current_exception();
    // This cycle's input says that the controller failed: the robot's command intake ends the
    // motion in a braking reflex, and the observer sees the cycle like any other (nothing sent).
    emulator_.step(CycleInput::controller_failed(reason));
    ++report_.cycles;
    if (options_.observer) options_.observer(emulator_.state(), CycleInfo{});
    std::rethrow_exception(error);
  }

  Emulator& emulator_;
  const Controller& controller_;
  const LoopOptions& options_;
  CommandChannel channel_;
  TimingReport report_;
  std::vector<double> compute_us_, latency_us_;
};

MotionResult run_lockstep(MotionRunner& runner) {
  Duration period(0);
  while (true) {
    Command command = runner.call_controller(period);
    runner.close_at_max_duration(command);
    runner.step(command, runner.network_delivers());
    period = Duration(1);
    if (runner.done()) break;
  }
  return runner.finish();
}

// Real-time scheduling for the loop thread: an error under kEnforce, else a warning to report.
std::optional<std::string> require_realtime(RealtimeConfig config) {
  const std::vector<std::string> missing = enable_realtime_scheduling();
  if (missing.empty()) return std::nullopt;
  std::string text = "no real-time scheduling (" + missing.front();
  for (std::size_t i = 1; i < missing.size(); ++i) text += "; " + missing[i];
  text += ")";
  if (config == RealtimeConfig::kEnforce) throw RealtimeError(text + "; use RealtimeConfig::kIgnore to run anyway");
  return text + ": running without, timing will suffer";
}

MotionResult run_realtime(MotionRunner& runner, const LoopOptions& options) {
  runner.latency_us().reserve(options.max_duration ? static_cast<std::size_t>(*options.max_duration * 1000) + 16 : 60000);

  int64_t deadline = monotonic_ns();
  Duration period(0);
  while (true) {
    deadline += kCycleNs;
    sleep_until_ns(deadline);
    runner.latency_us().push_back(static_cast<double>(monotonic_ns() - deadline) * 1e-3);

    Command command = runner.call_controller(period);
    runner.close_at_max_duration(command);
    // The command counts only if it is back before the next cycle begins (the FCI's rule).
    const int64_t late_cycles = (monotonic_ns() - deadline) / kCycleNs;
    if (late_cycles == 0) {
      runner.step(command, runner.network_delivers());
    } else {
      ++runner.report().overruns;
      for (int64_t k = 0; k < late_cycles && !runner.done(); ++k) runner.step(command, false);
      deadline += late_cycles * kCycleNs;   // those deadlines have passed
    }
    period = Duration(static_cast<uint64_t>(1 + late_cycles));
    if (runner.done()) break;
  }
  return runner.finish();
}

}  // namespace

CommandChannel::CommandChannel(const CommandFaults& faults) : faults_(faults), rng_(faults.seed) {}

bool CommandChannel::delivers(uint64_t cycle) {
  // Draw every random number every cycle so that one fault setting does not shift the others.
  const double loss_draw = uniform_(rng_);
  const double latency_us = faults_.latency_mean_us + faults_.latency_jitter_us * std::abs(normal_(rng_));
  for (const CommandFaults::Burst& burst : faults_.bursts) {
    const auto first = static_cast<uint64_t>(std::llround(burst.at / kDeltaT));
    if (cycle >= first && cycle < first + static_cast<uint64_t>(burst.count)) return false;
  }
  if (loss_draw < faults_.loss_probability) return false;
  return latency_us <= faults_.budget_us;
}

Percentiles percentiles(std::vector<double> samples) {
  Percentiles p;
  p.count = samples.size();
  if (samples.empty()) return p;
  std::sort(samples.begin(), samples.end());
  const auto at = [&](double fraction) {
    const auto index = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(samples.size()))) - 1;
    return samples[std::min(index, samples.size() - 1)];
  };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.max = samples.back();
  return p;
}

std::vector<std::string> enable_realtime_scheduling() {
  std::vector<std::string> missing;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) missing.push_back(std::string("mlockall: ") + std::strerror(errno));
  sched_param param{};
  param.sched_priority = sched_get_priority_max(SCHED_FIFO) - 1;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error != 0) missing.push_back(std::string("SCHED_FIFO: ") + std::strerror(error));
  return missing;
}

MotionResult run_motion(Emulator& emulator, ControlMode mode, const Controller& controller,
                        const LoopOptions& options) {
  std::optional<std::string> warning;
  if (options.clock == Clock::kRealtime) warning = require_realtime(options.realtime_config);   // before the motion
  emulator.start_motion(mode);
  MotionRunner runner(emulator, controller, options);
  if (warning) runner.report().warnings.push_back(*warning);
  return options.clock == Clock::kLockstep ? run_lockstep(runner) : run_realtime(runner, options);
}

}  // namespace csp::rt
