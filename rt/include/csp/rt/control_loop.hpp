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
#include <vector>

#include "csp/rt/emulator.hpp"
#include "csp/rt/statistics.hpp"

namespace csp::rt {

enum class Clock { kLockstep, kRealtime };

// libfranka RealtimeConfig: kEnforce fails without real-time scheduling, kIgnore warns and goes on.
enum class RealtimeConfig { kEnforce, kIgnore };

class RealtimeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

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

struct TimingReport {
  uint64_t cycles = 0;
  uint64_t lost_commands = 0;         // not received in their cycle (faults, overruns)
  uint64_t overruns = 0;              // real time: cycles whose controller call ended after the next deadline
  uint64_t missed_deadlines = 0;      // real time: deadlines those cycles skipped (DeadlineClock's rule)
  Percentiles controller_compute_us;  // wall time of the control callback
  Percentiles wakeup_latency_us;      // real time: wake-up after the absolute deadline
  std::vector<std::string> warnings;  // e.g. no real-time scheduling (kIgnore)
};

struct CycleInfo {
  bool command_sent = false;      // the controller produced a command this cycle
  bool command_received = false;  // and it reached the robot
  Command command;                // what was sent
};

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
  std::string reason;           // Emulator::reflex_reason()
  TimingReport timing;
};

// Starts a motion in `mode`, calls `controller` once per received state (the period is the time
// since the previous call: 0 first, 1 ms, more after an overrun), and steps the emulator until the
// controller returns motion_finished, max_duration passes, or a reflex ends the motion. A
// controller exception aborts the motion (Reflex), is reported to the observer, and is rethrown.
MotionResult run_motion(Emulator& emulator, ControlMode mode, const Controller& controller,
                        const LoopOptions& options);

// SCHED_FIFO and mlockall for the calling thread; returns what could not be had (empty: all).
std::vector<std::string> enable_realtime_scheduling();

}  // namespace csp::rt
