// The timing statistics and the deadline clock of the real-time loops: the streaming histogram
// against exact sorted quantiles, the clock's overrun rule on a fake time source.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "csp/rt/cycle_driver.hpp"
#include "csp/rt/deadline_clock.hpp"
#include "csp/rt/statistics.hpp"

namespace csp {
namespace {

using rt::DeadlineClock;
using rt::DurationHistogram;

// The nearest-rank quantile of a sorted sample: the value of rank ceil(q n).
double exact_quantile(const std::vector<double>& sorted, double q) {
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

// A quantile is the middle of the bucket holding the exact one; buckets above kLowest are at most
// 1/kSubBuckets of their lower edge wide, below it kLowest/kSubBuckets wide.
void expect_within_half_bucket(double reported, double exact, const char* what) {
  const double half_bucket = exact >= DurationHistogram::kLowest
                                 ? exact / (2.0 * DurationHistogram::kSubBuckets)
                                 : DurationHistogram::kLowest / (2.0 * DurationHistogram::kSubBuckets);
  EXPECT_LE(std::abs(reported - exact), half_bucket) << what << ": reported " << reported << ", exact " << exact;
}

void check_against_sorted(const std::function<double(std::mt19937_64&)>& draw, const char* name) {
  std::mt19937_64 rng(20261123);
  std::vector<double> samples(100'000);
  DurationHistogram histogram;
  for (double& s : samples) {
    s = draw(rng);
    histogram.add(s);
  }
  std::sort(samples.begin(), samples.end());
  SCOPED_TRACE(name);
  for (double q : {0.001, 0.1, 0.5, 0.9, 0.99, 0.999, 0.9999, 1.0})
    expect_within_half_bucket(histogram.quantile(q), exact_quantile(samples, q), "quantile");
  const rt::Percentiles p = histogram.percentiles();
  EXPECT_EQ(p.count, samples.size());
  EXPECT_EQ(p.max, samples.back()) << "the maximum is exact";
  expect_within_half_bucket(p.p50, exact_quantile(samples, 0.5), "p50");
  expect_within_half_bucket(p.p99, exact_quantile(samples, 0.99), "p99");
  expect_within_half_bucket(p.p999, exact_quantile(samples, 0.999), "p99.9");
}

TEST(DurationHistogram, QuantilesOfUniformSamples) {
  check_against_sorted([](std::mt19937_64& rng) { return std::uniform_real_distribution<double>(5.0, 1000.0)(rng); },
                       "uniform 5..1000 us");
}

TEST(DurationHistogram, QuantilesOfExponentialSamples) {
  check_against_sorted([](std::mt19937_64& rng) { return std::exponential_distribution<double>(1.0 / 40.0)(rng); },
                       "exponential, mean 40 us");
}

// Heavy-tailed like wake-up latencies: most near 50 us, a tail over decades up to seconds.
TEST(DurationHistogram, QuantilesOfLognormalSamples) {
  check_against_sorted([](std::mt19937_64& rng) { return std::lognormal_distribution<double>(std::log(50.0), 1.5)(rng); },
                       "lognormal, median 50 us");
}

// Two modes far apart, and values below kLowest (sub-nanosecond, the linear first buckets).
TEST(DurationHistogram, QuantilesOfBimodalSamplesDownToZero) {
  check_against_sorted(
      [](std::mt19937_64& rng) {
        if (std::bernoulli_distribution(0.3)(rng)) return std::uniform_real_distribution<double>(0.0, 0.002)(rng);
        return std::normal_distribution<double>(900.0, 30.0)(rng);
      },
      "bimodal: 0..2 ns and 900 +- 30 us");
}

TEST(DurationHistogram, EmptyAndClear) {
  DurationHistogram histogram;
  EXPECT_EQ(histogram.percentiles().count, 0u);
  EXPECT_EQ(histogram.quantile(0.5), 0.0);
  histogram.add(12.5);
  EXPECT_EQ(histogram.max(), 12.5);
  EXPECT_EQ(histogram.quantile(0.5), 12.5) << "one sample: every quantile is within the bucket and clamped to the max";
  histogram.clear();
  EXPECT_EQ(histogram.count(), 0u);
  EXPECT_EQ(histogram.max(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// The deadline clock's rule on a fake time source [ns].

int64_t fake_now = 0;
int64_t fake_clock() { return fake_now; }

constexpr int64_t kT = DeadlineClock::kPeriodNs;

TEST(DeadlineClock, WaitsForAbsoluteDeadlinesAndSpinsTheLastStretch) {
  fake_now = 5'000;
  DeadlineClock clock(fake_clock);
  EXPECT_EQ(clock.deadline_ns(), 5'000 + kT) << "the first deadline is one period after the start";
  EXPECT_EQ(clock.time_to_spin_ns(), kT - DeadlineClock::kSpinNs);
  EXPECT_FALSE(clock.reached());
  fake_now = 5'000 + kT - DeadlineClock::kSpinNs + 1;
  EXPECT_EQ(clock.time_to_spin_ns(), 0) << "inside the spin window: poll without blocking";
  EXPECT_FALSE(clock.reached());
  fake_now = 5'000 + kT + 7'000;   // 7 us late
  EXPECT_TRUE(clock.reached());
  fake_now += 3'000;
  EXPECT_TRUE(clock.reached()) << "still reached, latency recorded once";
  EXPECT_EQ(clock.end_cycle(), 0);
  EXPECT_EQ(clock.deadline_ns(), 5'000 + 2 * kT) << "absolute: the 7 us of lateness do not shift the grid";
  EXPECT_EQ(clock.wakeup_latency_us().count(), 1u);
  EXPECT_EQ(clock.wakeup_latency_us().max(), 7.0);
}

TEST(DeadlineClock, CountsOverrunsAndMissedDeadlinesByOneRule) {
  fake_now = 0;
  DeadlineClock clock(fake_clock);
  const auto cycle = [&](int64_t work_ends_after_deadline_ns) {
    fake_now = clock.deadline_ns();
    EXPECT_TRUE(clock.reached());
    fake_now += work_ends_after_deadline_ns;
    return clock.end_cycle();
  };
  EXPECT_EQ(cycle(kT - 1), 0) << "work ending just before the next deadline is on time";
  EXPECT_EQ(clock.overruns(), 0u);
  const int64_t before = clock.deadline_ns();
  EXPECT_EQ(cycle(kT), 1) << "ending at the next deadline misses it";
  EXPECT_EQ(clock.deadline_ns(), before + 2 * kT) << "the next cycle begins at the first deadline still ahead";
  EXPECT_EQ(cycle(3 * kT + 10), 3);
  EXPECT_EQ(cycle(0), 0);
  EXPECT_EQ(clock.overruns(), 2u);
  EXPECT_EQ(clock.missed_deadlines(), 4u);
  EXPECT_EQ(clock.wakeup_latency_us().count(), 4u);
  EXPECT_EQ(clock.wakeup_latency_us().max(), 0.0);
}

// The real clock: wait() returns at or after each deadline, on the 1 ms grid.
TEST(DeadlineClock, RealClockWakesAtOrAfterEachDeadline) {
  DeadlineClock clock;
  const int64_t first = clock.deadline_ns();
  for (int k = 0; k < 20; ++k) {
    const int64_t deadline = clock.deadline_ns();
    clock.wait();
    EXPECT_GE(rt::monotonic_ns(), deadline);
    clock.end_cycle();
  }
  EXPECT_EQ((clock.deadline_ns() - first) % kT, 0) << "deadlines stay on the grid";
  EXPECT_EQ(clock.wakeup_latency_us().count(), 20u);
}

// The cycle driver of every front end (rt::CycleDriver): the catch-up rule runs one robot cycle per
// missed deadline, stops where the run ends, and one report counts cycles, lost commands, round
// trips and the deadlines.
TEST(CycleDriver, CatchesUpMissedDeadlinesAndReportsThem) {
  fake_now = 0;
  rt::CycleDriver driver(rt::Clock::kRealtime, rt::RealtimeConfig::kIgnore, fake_clock);
  int robot_cycles = 0;
  const auto robot_cycle = [&] {
    ++robot_cycles;
    driver.count_cycle(true);   // a caught-up cycle has no command
  };
  fake_now = kT + 2'000;   // the first deadline, 2 us late
  EXPECT_TRUE(driver.deadline_reached());
  driver.add_round_trip_ns(40'000);
  driver.count_cycle(false);
  fake_now = kT + 3 * kT + 500'000;   // the cycle's work passed three more deadlines
  driver.catch_up(driver.end_cycle(), robot_cycle, [] { return true; });
  EXPECT_EQ(robot_cycles, 3) << "one robot cycle per missed deadline";
  fake_now = 5 * kT;   // the next deadline the grid kept
  EXPECT_TRUE(driver.deadline_reached());
  driver.count_cycle(false);
  fake_now = 5 * kT + 2 * kT;   // two missed, but the run ends after one more cycle
  driver.catch_up(driver.end_cycle(), robot_cycle, [&] { return driver.cycles() < 6; });
  EXPECT_EQ(robot_cycles, 4) << "the catch-up stops where the run ends";

  const rt::TimingReport report = driver.report();
  EXPECT_EQ(report.clock, rt::Clock::kRealtime);
  EXPECT_EQ(report.cycles, 6u);
  EXPECT_EQ(report.lost_commands, 4u);
  EXPECT_EQ(report.overruns, 2u);
  EXPECT_EQ(report.missed_deadlines, 5u);
  EXPECT_EQ(report.wakeup_latency_us.count, 2u);
  EXPECT_EQ(report.wakeup_latency_us.max, 2.0);
  EXPECT_EQ(report.round_trip_us.count, 1u);
  EXPECT_NEAR(report.round_trip_us.max, 40.0, 40.0 / rt::DurationHistogram::kSubBuckets);
  EXPECT_DOUBLE_EQ(report.wall_seconds, 7e-3);
  // What real-time scheduling obtained is said either way: obtained, or a warning naming why not.
  EXPECT_EQ(report.realtime.scheduling && report.realtime.memory_locked, report.realtime.problems.empty());
  EXPECT_EQ(report.warnings.empty(), report.realtime.problems.empty());
}

TEST(CycleDriver, LockstepNeverMissesADeadline) {
  rt::CycleDriver driver(rt::Clock::kLockstep);
  EXPECT_TRUE(driver.deadline_reached());
  EXPECT_EQ(driver.time_to_spin_ns(), 0);
  driver.count_cycle(false);
  EXPECT_EQ(driver.end_cycle(), 0);
  const rt::TimingReport report = driver.report();
  EXPECT_EQ(report.clock, rt::Clock::kLockstep);
  EXPECT_EQ(report.cycles, 1u);
  EXPECT_FALSE(report.realtime.scheduling) << "lockstep asks for no real-time scheduling";
  EXPECT_TRUE(report.warnings.empty());
  EXPECT_EQ(report.wakeup_latency_us.count, 0u);
}

}  // namespace
}  // namespace csp
