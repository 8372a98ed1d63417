#include "csp/rt/statistics.hpp"

#include <algorithm>
#include <cmath>

namespace csp::rt {

DurationHistogram::DurationHistogram() : buckets_(static_cast<std::size_t>(kSubBuckets) * (1 + kOctaves), 0) {}

std::size_t DurationHistogram::bucket_of(double value) {
  if (!(value >= 0.0)) value = 0.0;
  if (value < kLowest) return static_cast<std::size_t>(value / kLowest * kSubBuckets);
  // value / kLowest = m 2^k with m in [0.5, 1): octave e = k - 1, position 2m - 1 in [0, 1) within it.
  // kLowest and kSubBuckets are powers of two, so every step is exact.
  int k = 0;
  const double m = std::frexp(value / kLowest, &k);
  const int octave = k - 1;
  if (octave >= kOctaves) return static_cast<std::size_t>(kSubBuckets) * (1 + kOctaves) - 1;
  const auto sub = static_cast<std::size_t>((2.0 * m - 1.0) * kSubBuckets);
  return static_cast<std::size_t>(kSubBuckets) * (1 + octave) + sub;
}

double DurationHistogram::middle_of(std::size_t bucket) {
  if (bucket < static_cast<std::size_t>(kSubBuckets)) return (static_cast<double>(bucket) + 0.5) * kLowest / kSubBuckets;
  const int octave = static_cast<int>(bucket / kSubBuckets) - 1;
  const auto sub = static_cast<double>(bucket % kSubBuckets);
  const double width = std::ldexp(kLowest, octave) / kSubBuckets;
  return std::ldexp(kLowest, octave) + (sub + 0.5) * width;
}

void DurationHistogram::add(double value_us) {
  ++buckets_[bucket_of(value_us)];
  ++count_;
  if (value_us > max_) max_ = value_us;
}

void DurationHistogram::clear() {
  std::fill(buckets_.begin(), buckets_.end(), 0);
  count_ = 0;
  max_ = 0.0;
}

double DurationHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const auto rank = std::clamp<uint64_t>(static_cast<uint64_t>(std::ceil(q * static_cast<double>(count_))), 1, count_);
  uint64_t below = 0;
  for (std::size_t b = 0; b < buckets_.size(); ++b) {
    below += buckets_[b];
    // No quantile exceeds the maximum, which is known exactly.
    if (below >= rank) return std::min(middle_of(b), max_);
  }
  return max_;
}

Percentiles DurationHistogram::percentiles() const {
  Percentiles p;
  p.count = static_cast<std::size_t>(count_);
  p.p50 = quantile(0.5);
  p.p99 = quantile(0.99);
  p.p999 = quantile(0.999);
  p.max = max_;
  return p;
}

}  // namespace csp::rt
