#include "csp/rt/control_loop.hpp"

#include <cmath>
#include <exception>
#include <stdexcept>

namespace csp::rt {

MotionSession::MotionSession(Emulator& emulator, ControlMode mode, std::optional<ControllerMode> controller,
                             const LoopOptions& options)
    : emulator_(emulator), options_(options), channel_(options.faults), driver_(options.clock, options.realtime_config) {
  emulator_.start_motion(mode, controller);
}

Duration MotionSession::read() {
  if (done()) return Duration(0);
  if (awaiting_answer_) {
    // The state read last got no answer: its cycle (and, real time, the ones it overran) ran
    // without a command.
    const int64_t missed = driver_.end_cycle();
    if (!done()) step(std::nullopt, false);
    driver_.catch_up(missed, [&] { step(std::nullopt, false); }, [&] { return !done(); });
  }
  if (!done()) driver_.wait();
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
  driver_.add_round_trip_ns(monotonic_ns() - read_ns_);
  // The command of the last cycle of max_duration (or after a stop request) closes the motion, as
  // if the controller had marked it finished (a motion generator continues smoothly into it).
  const uint64_t cycles = driver_.cycles();
  if (options_.max_duration && static_cast<double>(cycles + 1) * kDeltaT >= *options_.max_duration - 1e-9)
    command.motion_finished = true;
  if (options_.stop && options_.stop->load()) command.motion_finished = true;
  // Real time: the command counts only if it is back before the next cycle begins. Late by
  // `missed` deadlines, it is lost, and so are the cycles that passed meanwhile: 1 + missed robot
  // cycles in all, the period the controller is told next.
  const int64_t missed = driver_.end_cycle();
  step(command, missed == 0 && channel_.delivers(cycles));
  driver_.catch_up(missed, [&] { step(command, false); }, [&] { return !done(); });
}

void MotionSession::fail(std::string_view reason) {
  awaiting_answer_ = false;
  if (done()) return;
  emulator_.step(CycleInput::controller_failed(reason));
  driver_.count_cycle(false);
  if (options_.observer) options_.observer(emulator_.state(), CycleInfo{});
}

void MotionSession::step(const std::optional<Command>& sent, bool arrived) {
  CycleInfo info;
  info.command_sent = sent.has_value();
  info.command_received = sent && arrived;
  if (sent) info.command = *sent;
  const bool lost = !info.command_received && emulator_.in_motion();
  emulator_.step(info.command_received ? &info.command : nullptr);
  driver_.count_cycle(lost);
  if (options_.observer) options_.observer(emulator_.state(), info);
}

MotionResult MotionSession::result() const {
  MotionResult result;
  result.reflex = emulator_.state().robot_mode == RobotMode::kReflex;
  result.errors = ErrorSet(emulator_.state().last_motion_errors);
  if (result.reflex) result.reason = emulator_.reflex_reason();
  result.timing = driver_.report();
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
