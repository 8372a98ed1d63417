// The cycle driver of every run: whatever brings the commands (a controller in this process,
// libfranka's API, the LCM bus, the CAN bus), the robot's cycles are paced, caught up and timed
// here, and every front end reports the same TimingReport.
//
// Two clocks:
//  - lockstep: a cycle runs when its command source is ready (the controller answered, the CAN
//    master's SYNC came, a source's timeout passed); robot time is simulated, runs reproduce bit
//    for bit;
//  - real time: DeadlineClock's absolute 1 kHz deadlines; at each one the robot steps with what
//    arrived before it.
//
// The catch-up rule (DeadlineClock's, one for all front ends): a cycle whose work ended after the
// next deadline missed the deadlines that passed meanwhile. The robot runs those cycles at once,
// without a command, as the FCI does, so that robot time keeps pace with the clock.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "csp/rt/deadline_clock.hpp"
#include "csp/rt/statistics.hpp"

namespace csp::rt {

enum class Clock { kLockstep, kRealtime };

const char* clock_name(Clock clock);   // "lockstep", "real-time"

// libfranka RealtimeConfig: kEnforce fails without real-time scheduling, kIgnore warns and goes on.
enum class RealtimeConfig { kEnforce, kIgnore };

class RealtimeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the process obtained of what a real-time loop needs.
struct RealtimeResources {
  bool scheduling = false;             // SCHED_FIFO for the loop's thread
  bool memory_locked = false;          // mlockall: no page fault in a cycle
  std::vector<std::string> problems;   // why not, one line each ("SCHED_FIFO: Operation not permitted")
};

// SCHED_FIFO and mlockall for the calling thread.
RealtimeResources enable_realtime_scheduling();

struct TimingReport {
  Clock clock = Clock::kLockstep;
  RealtimeResources realtime;          // real time only: what was obtained
  uint64_t cycles = 0;                 // robot cycles run
  uint64_t lost_commands = 0;          // motion cycles without a command (lost, late, not answered)
  uint64_t overruns = 0;               // real time: cycles whose work passed the next deadline
  uint64_t missed_deadlines = 0;       // real time: deadlines those cycles skipped (the catch-up rule)
  // State handed out -> its command back, in cycles of a control session only (not the wait for a
  // controller to start one): the controller's compute time in this process, publication ->
  // command received on a bus.
  Percentiles round_trip_us;
  Percentiles wakeup_latency_us;       // real time: the cycle began after its deadline
  double wall_seconds = 0.0;           // since the driver started
  std::vector<std::string> warnings;   // e.g. no real-time scheduling (kIgnore)
};

class CycleDriver {
 public:
  // Real time: real-time scheduling first; RealtimeError under kEnforce without it, a warning in
  // the report under kIgnore. `now_ns`: the deadline clock's time source (a test's fake).
  explicit CycleDriver(Clock clock, RealtimeConfig config = RealtimeConfig::kIgnore, int64_t (*now_ns)() = monotonic_ns);

  Clock clock() const { return clock_ ? Clock::kRealtime : Clock::kLockstep; }

  // Real time: blocks until the cycle's deadline. Lockstep: returns at once.
  void wait();
  // For a front end that keeps receiving while it waits (real time; lockstep: always true / 0).
  bool deadline_reached();
  int64_t time_to_spin_ns() const;

  // Ends the cycle begun at the deadline: the deadlines its work passed (0 on time, always 0 in
  // lockstep). Call catch_up with them once the cycle's own step ran.
  int64_t end_cycle();
  // The catch-up rule: `robot_cycle` (a cycle without a new command) once per missed deadline,
  // while `more()` (the run goes on: its duration not reached, its motion not ended).
  template <typename RobotCycle, typename More>
  void catch_up(int64_t missed, const RobotCycle& robot_cycle, const More& more) {
    for (int64_t k = 0; k < missed && more(); ++k) robot_cycle();
  }

  // Counted by the front end as its robot runs.
  void count_cycle(bool lost_command);
  void add_round_trip_ns(int64_t ns);
  uint64_t cycles() const { return report_.cycles; }

  TimingReport report() const;

 private:
  std::optional<DeadlineClock> clock_;
  int64_t (*now_ns_)();
  TimingReport report_;
  DurationHistogram round_trip_us_;
  int64_t start_ns_;
};

// A network front end's bus as the cycle driver paces it (csp serve's LCM, csp fci's sockets):
// messages arrive whenever they do, the robot steps once a cycle.
class MessageBus {
 public:
  virtual ~MessageBus() = default;
  // Handles the messages that arrive within `wait_ns` (0: only those already there).
  virtual void receive_for(int64_t wait_ns) = 0;
  // A control session runs (its cycles want commands) and this cycle's command has arrived.
  virtual bool in_session() const = 0;
  virtual bool answered() const = 0;
  // Steps the robot with the command that answered its state, or none, and sends the new state;
  // counts the cycle with `driver`.
  virtual void robot_cycle(CycleDriver& driver) = 0;
  // Sends the current state again (lockstep: a controller that missed it is not stuck).
  virtual void repeat_state() = 0;
  virtual bool stopped() const = 0;
};

struct BusPacing {
  uint64_t cycles = UINT64_MAX;       // robot cycles to run (UINT64_MAX: until the bus is stopped)
  double lockstep_timeout = 1.0;      // lockstep: how long a session's cycle waits for its command [s]
  bool wait_for_controller = false;   // lockstep: hold the first cycle until a session starts
};

// Runs `bus`'s cycles on `driver`'s clock (the first state must be sent already). Real time: at
// each deadline the robot steps with the command received since the last state (the FCI's rule:
// in time only if before this deadline), and missed deadlines are caught up. Lockstep: idle cycles
// pass at the wall-clock pace (a controller may start a session); a session's cycle waits for its
// command up to the timeout, repeating its state every 10 ms. Returns the wall time the session
// cycles took [s] (lockstep: the controller's pace).
double run_bus_cycles(MessageBus& bus, CycleDriver& driver, const BusPacing& pacing);

}  // namespace csp::rt
