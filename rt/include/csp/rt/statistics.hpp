// Timing statistics of the 1 kHz loops in constant memory: a week-long run keeps the same
// footprint as a second-long one, and recording a sample never allocates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace csp::rt {

// p50 / p99 / p99.9 / max of a sample [us]; quantiles by nearest rank.
struct Percentiles {
  double p50 = 0.0, p99 = 0.0, p999 = 0.0, max = 0.0;
  std::size_t count = 0;
};

// A streaming histogram of durations [us] with log-linear buckets, as HdrHistogram: below
// kLowest the range [0, kLowest) is cut into kSubBuckets equal buckets, and every octave
// [kLowest 2^e, kLowest 2^(e+1)) above it likewise, up to kOctaves octaves (about 1100 s; longer
// values share the last bucket). A quantile is reported as the middle of the bucket holding the
// sample of that rank, so it is off by at most half a bucket: a relative error of at most
// 1 / (2 kSubBuckets) = 0.39 % above kLowest, an absolute one of kLowest / (2 kSubBuckets) below.
// The maximum and the count are exact. Negative values and NaN count as 0.
class DurationHistogram {
 public:
  static constexpr int kSubBuckets = 128;
  static constexpr int kOctaves = 40;
  static constexpr double kLowest = 1.0 / 1024.0;   // [us], about 1 ns

  DurationHistogram();   // the only allocation: the bucket array

  void add(double value_us);
  void clear();

  // The sample of rank ceil(q n), 0 < q <= 1, to within half a bucket (0 when empty).
  double quantile(double q) const;
  Percentiles percentiles() const;
  uint64_t count() const { return count_; }
  double max() const { return max_; }

 private:
  static std::size_t bucket_of(double value);
  static double middle_of(std::size_t bucket);

  std::vector<uint64_t> buckets_;
  uint64_t count_ = 0;
  double max_ = 0.0;
};

}  // namespace csp::rt
