#include "csp/rt/deadline_clock.hpp"

#include <time.h>

#include <cerrno>

namespace csp::rt {

int64_t monotonic_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

DeadlineClock::DeadlineClock(int64_t (*now_ns)()) : now_ns_(now_ns), deadline_(now_ns() + kPeriodNs) {}

void DeadlineClock::wait() {
  const int64_t wake = deadline_ - kSpinNs;
  const timespec t{wake / 1'000'000'000, wake % 1'000'000'000};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
  while (!reached()) {
  }
}

int64_t DeadlineClock::time_to_spin_ns() const {
  const int64_t left = deadline_ - kSpinNs - now_ns_();
  return left > 0 ? left : 0;
}

bool DeadlineClock::reached() {
  if (reached_) return true;
  const int64_t now = now_ns_();
  if (now < deadline_) return false;
  reached_ = true;
  latency_us_.add(static_cast<double>(now - deadline_) * 1e-3);
  return true;
}

int64_t DeadlineClock::end_cycle() {
  const int64_t missed = (now_ns_() - deadline_) / kPeriodNs;   // 0 while the work ends before D + T
  if (missed > 0) {
    ++overruns_;
    missed_ += static_cast<uint64_t>(missed);
  }
  deadline_ += (1 + (missed > 0 ? missed : 0)) * kPeriodNs;
  reached_ = false;
  return missed > 0 ? missed : 0;
}

}  // namespace csp::rt
