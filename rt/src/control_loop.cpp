#include "csp/rt/control_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>


namespace csp::rt {
namespace {

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

}  // namespace

MotionSession::MotionSession(Emulator& emulator, ControlMode mode, std::optional<ControllerMode> controller,
                             const LoopOptions& options)
    : emulator_(emulator), options_(options), channel_(options.faults) {
  std::optional<std::string> warning;
  if (options.clock == Clock::kRealtime) warning = require_realtime(options.realtime_config);   // before the motion
  emulator_.start_motion(mode, controller);
  if (warning) report_.warnings.push_back(*warning);
  if (options.clock == Clock::kRealtime) clock_.emplace();
}

Duration MotionSession::read() {
  if (done()) return Duration(0);
  if (awaiting_answer_) {
    // The state read last got no answer: its cycle (and, real time, the ones it overran) ran
    // without a command.
    const int64_t missed = clock_ ? clock_->end_cycle() : 0;
    for (int64_t k = 0; k <= missed && !done(); ++k) step(std::nullopt, false);
  }
  if (clock_ && !done()) clock_->wait();
  const Duration now = emulator_.state().time;
  const Duration period = first_read_ ? Duration(0) : now - last_read_time_;
  first_read_ = false;
  last_read_time_ = now;
  awaiting_answer_ = !done();
  read_ns_ = monotonic_ns();
  return period;
}

void MotionSession::write(Command command) {
  if (!awaiting_answer_) throw std::logic_error("a command must answer a state: read() the next state first");
  awaiting_answer_ = false;
  compute_us_.add(static_cast<double>(monotonic_ns() - read_ns_) * 1e-3);
  // The command of the last cycle of max_duration (or after a stop request) closes the motion, as
  // if the controller had marked it finished (a motion generator continues smoothly into it).
  if (options_.max_duration && static_cast<double>(report_.cycles + 1) * kDeltaT >= *options_.max_duration - 1e-9)
    command.motion_finished = true;
  if (options_.stop && options_.stop->load()) command.motion_finished = true;
  // Real time: the command counts only if it is back before the next cycle begins. Late by
  // `missed` deadlines, it is lost, and so are the cycles that passed meanwhile: 1 + missed robot
  // cycles in all, the period the controller is told next.
  const int64_t missed = clock_ ? clock_->end_cycle() : 0;
  step(command, missed == 0 && channel_.delivers(report_.cycles));
  for (int64_t k = 0; k < missed && !done(); ++k) step(command, false);
}

void MotionSession::fail(std::string_view reason) {
  awaiting_answer_ = false;
  if (done()) return;
  emulator_.step(CycleInput::controller_failed(reason));
  ++report_.cycles;
  if (options_.observer) options_.observer(emulator_.state(), CycleInfo{});
}

void MotionSession::step(const std::optional<Command>& sent, bool arrived) {
  CycleInfo info;
  info.command_sent = sent.has_value();
  info.command_received = sent && arrived;
  if (sent) info.command = *sent;
  if (!info.command_received && emulator_.in_motion()) ++report_.lost_commands;
  emulator_.step(info.command_received ? &info.command : nullptr);
  ++report_.cycles;
  if (options_.observer) options_.observer(emulator_.state(), info);
}

MotionResult MotionSession::result() const {
  MotionResult result;
  result.reflex = emulator_.state().robot_mode == RobotMode::kReflex;
  result.errors = ErrorSet(emulator_.state().last_motion_errors);
  result.reason = emulator_.reflex_reason();
  result.timing = report_;
  result.timing.controller_compute_us = compute_us_.percentiles();
  if (clock_) {
    result.timing.overruns = clock_->overruns();
    result.timing.missed_deadlines = clock_->missed_deadlines();
    result.timing.wakeup_latency_us = clock_->wakeup_latency_us().percentiles();
  }
  return result;
}

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
                        const LoopOptions& options, std::optional<ControllerMode> controller_mode) {
  MotionSession session(emulator, mode, controller_mode, options);
  while (!session.done()) {
    const Duration period = session.read();
    Command command;
    try {
      command = controller(session.state(), period);
    } catch (const std::exception& e) {
      session.fail("the controller threw: " + std::string(e.what()));
      throw;
    } catch (...) {
      session.fail("the controller threw a non-standard exception");
      throw;
    }
    session.write(command);
  }
  return session.result();
}

}  // namespace csp::rt
