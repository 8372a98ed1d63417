// Running a motion on the emulator with a controller in the same process, on one of two clocks:
// lockstep (simulated time, 1 ms per cycle, bit-reproducible) or real time (the DeadlineClock's
// absolute 1 kHz deadlines). Commands pass a seeded network model that can lose them.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "csp/rt/cycle_driver.hpp"
#include "csp/rt/emulator.hpp"

namespace csp::rt {

// The network between controller and robot, seeded: each command is lost with
// `loss_probability`, or arrives after a latency (mean + |normal jitter|) that may miss the
// cycle's budget and so be lost as on the FCI; scripted bursts lose `count` commands in a row
// from motion time `at` [s].
struct CommandFaults {
  double loss_probability = 0.0;
  double latency_mean_us = 0.0;
  double latency_jitter_us = 0.0;
  double budget_us = 1000.0;
  struct Burst {
    double at = 0.0;
    int count = 0;
  };
  std::vector<Burst> bursts;
  uint64_t seed = 1;
};

class CommandChannel {
 public:
  explicit CommandChannel(const CommandFaults& faults);
  // Whether the command sent in motion cycle `cycle` (0-based) reaches the robot in time.
  bool delivers(uint64_t cycle);

 private:
  CommandFaults faults_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::normal_distribution<double> normal_{0.0, 1.0};
};

struct CycleInfo {
  bool command_sent = false;      // the controller produced a command this cycle
  bool command_received = false;  // and it reached the robot
  Command command;                // what was sent
};

// A cycle as a server on a network sees it: only what arrived (a command sent but lost on the way
// is not known there). `applied`: the command the cycle applied, if one was received.
inline CycleInfo received_cycle(bool command_received, const Command& applied) {
  CycleInfo cycle;
  cycle.command_sent = command_received;
  cycle.command_received = command_received;
  if (command_received) cycle.command = applied;
  return cycle;
}

using Controller = std::function<Command(const RobotState&, Duration)>;
using CycleObserver = std::function<void(const RobotState&, const CycleInfo&)>;

struct LoopOptions {
  Clock clock = Clock::kLockstep;
  RealtimeConfig realtime_config = RealtimeConfig::kIgnore;
  CommandFaults faults;
  std::optional<double> max_duration;   // [s]: end the motion normally after this long
  // Set (by a signal handler, another thread or the observer) to end the motion as at
  // max_duration: the next command carries motion_finished.
  const std::atomic<bool>* stop = nullptr;
  CycleObserver observer;               // called after every cycle with the published state
};

struct MotionResult {
  bool reflex = false;          // the motion ended in a reflex (see errors and reason)
  ErrorSet errors;                // the errors that aborted it
  std::string reason;           // Emulator::reflex_reason() if this motion ended in a reflex
  TimingReport timing;   // round_trip_us: the controller's compute time
};

// One motion as the FCI runs it, for every front end in this process: the robot publishes a state
// each 1 ms cycle; the controller reads it and answers with one command. The rules (the FCI's):
//  - read() before write(): each command answers the state read last (std::logic_error otherwise);
//  - a state read and not answered before the next read lost its command: that cycle runs without
//    one (the robot extrapolates; 20 in a row end the motion in communication_constraints_violation);
//  - real time: an answer must be back before the next deadline; a late one is lost, and so are the
//    cycles that passed meanwhile (DeadlineClock's rule). Lockstep: the robot waits for each answer.
// run_motion (a callback per state) and libfranka's external control loop (franka/active_control.h:
// readOnce/writeOnce) both run on it.
class MotionSession {
 public:
  // Starts the motion in `mode`, tracked by the robot's `controller` (Emulator::start_motion). On the
  // real-time clock, real-time scheduling first: RealtimeError under kEnforce, a warning under kIgnore.
  MotionSession(Emulator& emulator, ControlMode mode, std::optional<ControllerMode> controller,
                const LoopOptions& options);

  // The next state to answer (state()); returns the robot time since the previous read (0 at the
  // first). After the motion ended (done()) it returns 0 and the robot stays as it is.
  Duration read();
  const RobotState& state() const { return emulator_.state(); }
  // The answer to the state read last. options.max_duration or options.stop make it the last.
  void write(Command command);
  // The controller failed on the state read last (it threw, or sent what libfranka refuses): the
  // robot's command intake ends the motion in a reflex with `reason`.
  void fail(std::string_view reason);
  // The motion ended: its last command was received, or a reflex stopped it.
  bool done() const { return !emulator_.in_motion(); }
  // Whether a state was read and not yet answered.
  bool awaiting_answer() const { return awaiting_answer_; }
  // The outcome and the timing so far.
  MotionResult result() const;

 private:
  void step(const std::optional<Command>& sent, bool arrived);

  Emulator& emulator_;
  const LoopOptions& options_;
  CommandChannel channel_;
  CycleDriver driver_;
  bool awaiting_answer_ = false;
  bool first_read_ = true;
  Duration last_read_time_;
  int64_t read_ns_ = 0;   // when the state read last was handed out
};

// Runs a whole motion on a MotionSession: calls `controller` once per state until it returns
// motion_finished, max_duration passes, or a reflex ends the motion. A controller exception aborts
// the motion (MotionSession::fail), is reported to the observer, and is rethrown.
MotionResult run_motion(Emulator& emulator, ControlMode mode, const Controller& controller,
                        const LoopOptions& options, std::optional<ControllerMode> controller_mode = std::nullopt);

}  // namespace csp::rt
