#include "csp/gap/idle.hpp"

#include <string>
#include <utility>
#include <vector>

namespace csp::gap {

bool at_rest(const Vector7& dq, const IdleOptions& options) { return dq.cwiseAbs().maxCoeff() < options.velocity; }

IdleTrim leave_out_idle(const JointLog& log, const FilterOptions& filter, const IdleOptions& options) {
  const Samples samples = filter_log(log, filter);
  const std::size_t n = log.size();
  // Each row is idle when the last sample at or before it is (the first sample's rows before it).
  std::vector<bool> idle(n);
  for (std::size_t k = 0, s = 0; k < n; ++k) {
    while (s + 1 < samples.size() && samples.t[s + 1] <= log.t[k]) ++s;
    idle[k] = at_rest(samples.dq[s], options);
  }

  // The rows kept, as [begin, end) ranges between the stretches left out.
  IdleTrim trim;
  std::vector<std::pair<std::size_t, std::size_t>> kept;
  std::size_t next = 0;
  for (std::size_t a = 0; a < n; ++a) {
    if (!idle[a]) continue;
    std::size_t b = a;
    while (b + 1 < n && idle[b + 1]) ++b;
    const bool at_start = a == 0, at_end = b + 1 == n;
    if (at_start && at_end)
      throw JointLogError(log.source + ": the arm does not move (every joint slower than " + std::to_string(options.velocity) +
                          " rad/s throughout): no motion to diagnose");
    if (log.t[b] - log.t[a] >= options.min_duration) {
      const double cut_begin = at_start ? log.t[a] : log.t[a] + options.margin;
      const double cut_end = at_end ? log.t[b] : log.t[b] - options.margin;
      std::size_t first_out = a, last_out = b;
      while (log.t[first_out] < cut_begin) ++first_out;
      while (log.t[last_out] > cut_end) --last_out;
      if (first_out > next) kept.emplace_back(next, first_out);
      next = last_out + 1;
      ++trim.stretches;
    }
    a = b;
  }
  if (trim.stretches == 0) {
    trim.log = log;
    return trim;
  }
  if (next < n) kept.emplace_back(next, n);

  trim.log.source = log.source;
  double shift = 0.0;   // a range starts one time step after the previous one ends
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const auto [begin, end] = kept[i];
    if (i > 0) shift += log.t[begin - 1] - log.t[kept[i - 1].second - 1];
    append_rows(trim.log, slice(log, log.t[begin], end < n ? log.t[end] : log.t.back() + 1.0), shift);
  }
  trim.seconds_left_out = (log.t.back() - log.t.front()) - (trim.log.t.back() - trim.log.t.front());
  return trim;
}

double idle_fraction(const Samples& samples, const IdleOptions& options) {
  if (samples.size() == 0) return 0.0;
  std::size_t idle = 0;
  for (const Vector7& dq : samples.dq) idle += at_rest(dq, options) ? 1 : 0;
  return static_cast<double>(idle) / static_cast<double>(samples.size());
}

}  // namespace csp::gap
