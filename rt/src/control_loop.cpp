#include "csp/rt/control_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cmath>
#include <cstring>
#include <exception>

#include "csp/rt/deadline_clock.hpp"

namespace csp::rt {
namespace {

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
      compute_us_.add(static_cast<double>(monotonic_ns() - start) * 1e-3);
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

  // The controller's command of the last cycle of max_duration (or after a stop request) closes the
  // motion, as if it had returned MotionFinished (a motion generator continues smoothly into it).
  void close_when_due(Command& command) const {
    if (options_.max_duration && static_cast<double>(report_.cycles + 1) * kDeltaT >= *options_.max_duration - 1e-9)
      command.motion_finished = true;
    if (options_.stop && options_.stop->load()) command.motion_finished = true;
  }

  MotionResult finish() {
    MotionResult result;
    result.reflex = emulator_.state().robot_mode == RobotMode::kReflex;
    result.errors = ErrorSet(emulator_.state().last_motion_errors);
    result.reason = emulator_.reflex_reason();
    report_.controller_compute_us = compute_us_.percentiles();
    result.timing = report_;
    return result;
  }

  TimingReport& report() { return report_; }

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
  DurationHistogram compute_us_;
};

MotionResult run_lockstep(MotionRunner& runner) {
  Duration period(0);
  while (true) {
    Command command = runner.call_controller(period);
    runner.close_when_due(command);
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

MotionResult run_realtime(MotionRunner& runner) {
  DeadlineClock clock;
  Duration period(0);
  while (true) {
    clock.wait();
    Command command = runner.call_controller(period);
    runner.close_when_due(command);
    // The command counts only if it is back before the next cycle begins (the FCI's rule). Late
    // by `missed` deadlines, it is lost, and so are the cycles that passed meanwhile and the one the
    // clock skips to stay on the grid: 1 + missed robot cycles in all, the period the controller is
    // told next (libfranka's period is the robot time between two calls).
    const int64_t missed = clock.end_cycle();
    runner.step(command, missed == 0 && runner.network_delivers());
    for (int64_t k = 0; k < missed && !runner.done(); ++k) runner.step(command, false);
    period = Duration(static_cast<uint64_t>(1 + missed));
    if (runner.done()) break;
  }
  TimingReport& report = runner.report();
  report.overruns = clock.overruns();
  report.missed_deadlines = clock.missed_deadlines();
  report.wakeup_latency_us = clock.wakeup_latency_us().percentiles();
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
  return options.clock == Clock::kLockstep ? run_lockstep(runner) : run_realtime(runner);
}

}  // namespace csp::rt
