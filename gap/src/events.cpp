#include "csp/gap/events.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace csp::gap {
namespace {

using Eigen::VectorXd;

// A burst: a run of stretches of one joint's residual above kEventRatio times the median stretch.
struct Burst {
  std::size_t part = 0;
  std::size_t peak = 0;          // the sample of the largest |residual| in the run
  std::size_t first = 0, last = 0;  // the run's samples
};

double residual(const VectorXd& left, std::size_t k, int j) {
  return left[static_cast<Eigen::Index>(kNumJoints * k) + j];
}

// The times at which `value(k)` changes sign, each at least kEventWindow after the last (the filtered
// signals cross zero once, but a slow crossing may graze it twice).
template <class Value>
std::vector<double> sign_changes(const Samples& s, Value value) {
  std::vector<double> times;
  for (std::size_t k = 1; k < s.size(); ++k)
    if (value(k - 1) * value(k) < 0.0 && (times.empty() || s.t[k] - times.back() > kEventWindow)) times.push_back(s.t[k]);
  return times;
}

// How many of `times` have an entry of `near` within kEventLock (both sorted).
int within_lock(const std::vector<double>& times, const std::vector<double>& near) {
  int count = 0;
  for (double t : times) {
    const auto after = std::lower_bound(near.begin(), near.end(), t - kEventLock);
    count += after != near.end() && *after <= t + kEventLock ? 1 : 0;
  }
  return count;
}

// One candidate lock of a joint's bursts: which of them it holds, and the occasions it covers.
struct Lock {
  MotionEvent::Kind kind = MotionEvent::Kind::kReversal;
  int from_joint = 0;
  double position = 0.0;
  std::vector<std::size_t> bursts;  // indices into the joint's bursts
  int occasions = 0, covered = 0;
};

// The lock of `bursts` to the reversals of joint i, or to its passes through the bursts' median position.
Lock lock_to(MotionEvent::Kind kind, int i, const std::vector<Burst>& bursts, const std::array<const Part*, 2>& parts) {
  Lock lock;
  lock.kind = kind, lock.from_joint = i + 1;
  if (kind == MotionEvent::Kind::kPosition) {
    std::vector<double> at;
    for (const Burst& b : bursts) at.push_back(parts[b.part]->samples.q[b.peak][i]);
    std::nth_element(at.begin(), at.begin() + static_cast<std::ptrdiff_t>(at.size() / 2), at.end());
    lock.position = at[at.size() / 2];
  }
  for (std::size_t p = 0; p < 2; ++p) {
    const Samples& s = parts[p]->samples;
    const std::vector<double> occasions =
        kind == MotionEvent::Kind::kReversal
            ? sign_changes(s, [&](std::size_t k) { return s.dq[k][i]; })
            : sign_changes(s, [&](std::size_t k) { return s.q[k][i] - lock.position; });
    std::vector<double> locked_times;
    for (std::size_t b = 0; b < bursts.size(); ++b) {
      if (bursts[b].part != p) continue;
      const double t = s.t[bursts[b].peak];
      // At a reversal; or at the position (a reversal inside the bump's span has no pass, but a burst).
      const bool locked = kind == MotionEvent::Kind::kReversal
                              ? within_lock({t}, occasions) == 1
                              : std::abs(s.q[bursts[b].peak][i] - lock.position) <= kEventPositionLock;
      if (locked) lock.bursts.push_back(b), locked_times.push_back(t);
    }
    lock.occasions += static_cast<int>(occasions.size());
    lock.covered += within_lock(occasions, locked_times);
  }
  return lock;
}

bool holds(const Lock& lock, std::size_t bursts) {
  const auto locked = static_cast<double>(lock.bursts.size());
  return lock.bursts.size() >= static_cast<std::size_t>(kEventMinimum) &&
         locked >= kEventLockedShare * static_cast<double>(bursts) &&
         lock.covered >= kEventCoverage * static_cast<double>(lock.occasions);
}

}  // namespace

std::vector<MotionEvent> find_motion_events(const std::array<const Part*, 2>& parts,
                                            const std::array<const VectorXd*, 2>& left) {
  // Each joint's stretch mean squares in both parts, and their median.
  std::array<std::size_t, 2> width{};
  std::array<std::vector<Vector7>, 2> stretch_ms;
  std::array<std::vector<double>, kNumJoints> pooled;
  for (std::size_t p = 0; p < 2; ++p) {
    if (parts[p]->samples.size() < 2) return {};
    const Stretches stretches = stretch_mean_squares(parts[p]->samples, *left[p], kEventWindow);
    width[p] = stretches.width, stretch_ms[p] = stretches.mean_square;
    for (const Vector7& ms : stretch_ms[p])
      for (int j = 0; j < kNumJoints; ++j) pooled[j].push_back(ms[j]);
  }
  std::vector<MotionEvent> events;
  for (int j = 0; j < kNumJoints; ++j) {
    if (pooled[j].size() < 4) continue;
    std::nth_element(pooled[j].begin(), pooled[j].begin() + static_cast<std::ptrdiff_t>(pooled[j].size() / 2),
                     pooled[j].end());
    const double threshold = kEventRatio * kEventRatio * pooled[j][pooled[j].size() / 2];
    // The bursts: runs of stretches above the threshold, each at its largest sample.
    std::vector<Burst> bursts;
    double total = 0.0;
    for (std::size_t p = 0; p < 2; ++p) {
      const std::size_t stretches = stretch_ms[p].size(), n = parts[p]->samples.size();
      for (std::size_t k = 0; k < n; ++k) total += std::pow(residual(*left[p], k, j), 2);
      for (std::size_t w = 0; w < stretches;) {
        if (!(stretch_ms[p][w][j] > threshold)) {
          ++w;
          continue;
        }
        std::size_t end = w;
        while (end < stretches && stretch_ms[p][end][j] > threshold) ++end;
        Burst b{p, w * width[p], w * width[p], std::min(end * width[p], n) - 1};
        for (std::size_t k = b.first; k <= b.last; ++k)
          if (std::abs(residual(*left[p], k, j)) > std::abs(residual(*left[p], b.peak, j))) b.peak = k;
        bursts.push_back(b);
        w = end;
      }
    }
    if (bursts.size() < static_cast<std::size_t>(kEventMinimum)) continue;
    // The lock that holds most bursts: reversals before positions, the joint's own first.
    std::optional<Lock> best;
    for (MotionEvent::Kind kind : {MotionEvent::Kind::kReversal, MotionEvent::Kind::kPosition})
      for (int offset = 0; offset < kNumJoints; ++offset) {
        const int i = (j + offset) % kNumJoints;
        Lock lock = lock_to(kind, i, bursts, parts);
        if (holds(lock, bursts.size()) && (!best || lock.bursts.size() > best->bursts.size())) best = std::move(lock);
      }
    if (!best) continue;
    MotionEvent e;
    e.kind = best->kind, e.joint = j + 1, e.from_joint = best->from_joint, e.position = best->position;
    e.occasions = best->occasions, e.covered = best->covered;
    double sum = 0.0;
    std::size_t samples = 0;
    for (std::size_t index : best->bursts) {
      const Burst& b = bursts[index];
      e.times.push_back(parts[b.part]->samples.t[b.peak]);
      e.in_heldout.push_back(b.part == 1);
      for (std::size_t k = b.first; k <= b.last; ++k) sum += std::pow(residual(*left[b.part], k, j), 2);
      samples += b.last - b.first + 1;
    }
    e.size = std::sqrt(sum / static_cast<double>(samples));
    e.share = total > 0.0 ? sum / total : 0.0;
    events.push_back(std::move(e));
  }
  return events;
}

bool has_burst_within(const MotionEvent& event, bool heldout, double start, double end) {
  for (std::size_t i = 0; i < event.times.size(); ++i)
    if (event.in_heldout[i] == heldout && event.times[i] >= start && event.times[i] <= end) return true;
  return false;
}

}  // namespace csp::gap
