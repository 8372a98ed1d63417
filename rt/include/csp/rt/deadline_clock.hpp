// The 1 kHz real-time clock of every front end (the in-process loop, `csp serve`, the CAN bus):
// absolute deadlines on CLOCK_MONOTONIC, so that a late cycle never shifts the ones after it.
//
// The rule, one for all front ends: a cycle begins at its deadline D, and its work (controller,
// robot step, publication) must end before the next deadline D + T (T = 1 ms). Work that ends at
// t >= D + T overran: the floor((t - D) / T) deadlines that passed during it are missed (the robot
// runs those cycles without a command, as the FCI does), and the next cycle begins at the first
// deadline after t, keeping the 1 ms grid rather than catching up in a burst.
//
// Use, for a loop with nothing else to do:
//   DeadlineClock clock;
//   while (running) { clock.wait(); work(); clock.end_cycle(); }
// and for a front end that must keep receiving while it waits (messages, CAN frames):
//   while (!clock.reached()) poll_for_input(clock.time_to_spin_ns());   // 0: poll without blocking
#pragma once

#include <cstdint>

#include "csp/rt/statistics.hpp"

namespace csp::rt {

// CLOCK_MONOTONIC [ns].
int64_t monotonic_ns();

class DeadlineClock {
 public:
  static constexpr int64_t kPeriodNs = 1'000'000;
  // Waking from a sleep costs tens of microseconds on a kernel without PREEMPT_RT: sleep until
  // this long before the deadline, then spin to it.
  static constexpr int64_t kSpinNs = 100'000;

  // The first deadline is one period from now. `now_ns` is the time source: CLOCK_MONOTONIC, or
  // a test's fake (wait() sleeps on CLOCK_MONOTONIC itself, so a fake suits the other calls only).
  explicit DeadlineClock(int64_t (*now_ns)() = monotonic_ns);

  // Sleeps until kSpinNs before the deadline, then spins until it is reached.
  void wait();
  // How long a front end may block before it has to spin [ns]; 0 once it has to spin.
  int64_t time_to_spin_ns() const;
  // Whether the deadline has come; the first true of a cycle records the wake-up latency.
  bool reached();
  // Ends the cycle begun at the deadline (the rule above): returns the deadlines missed, 0 when
  // on time, and moves to the next deadline.
  int64_t end_cycle();

  int64_t deadline_ns() const { return deadline_; }
  uint64_t overruns() const { return overruns_; }               // cycles whose work passed the next deadline
  uint64_t missed_deadlines() const { return missed_; }         // deadlines those cycles skipped
  const DurationHistogram& wakeup_latency_us() const { return latency_us_; }   // reached() after the deadline

 private:
  int64_t (*now_ns_)();
  int64_t deadline_;
  bool reached_ = false;
  uint64_t overruns_ = 0, missed_ = 0;
  DurationHistogram latency_us_;
};

}  // namespace csp::rt
