// Recurring events tied to the motion (docs/gap.md, "Events"): short bursts of the residual left on
// one joint that come back at the velocity reversals of a joint (a knock or a ringing as the gears
// take up their play), or each time a joint passes one position (a cable that catches, a damaged
// tooth). Told apart from isolated disturbances (a push, a contact: Transient), which the selection
// leaves out; a recurring event is the robot's own behaviour, and the selection keeps it.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "csp/gap/part.hpp"

namespace csp::gap {

inline constexpr double kEventWindow = 0.1;         // [s] stretches of the residual whose RMS finds bursts
inline constexpr double kEventRatio = 3.0;          // a burst: a stretch's RMS above this many times the joint's median
inline constexpr double kEventLock = 0.2;           // [s] a burst this close to a reversal or a pass is locked to it
inline constexpr double kEventPositionLock = 0.03;  // [rad] bursts at one position: this close to their median
inline constexpr int kEventMinimum = 4;             // bursts (both parts) for a recurring event
inline constexpr double kEventLockedShare = 0.75;   // of a joint's bursts locked to the same motion
inline constexpr double kEventCoverage = 0.5;       // of the reversals (passes) that have a burst

struct MotionEvent {
  enum class Kind { kReversal, kPosition };
  Kind kind = Kind::kReversal;
  int joint = 0;                // 1-based: where the bursts are
  int from_joint = 0;           // 1-based: whose reversals, or whose position
  double position = 0.0;        // [rad] kPosition: where from_joint is at the bursts
  std::vector<double> times;    // [s] the locked bursts' peaks, each in its part's time
  std::vector<bool> in_heldout; // per entry of times: in the held-out part (else the training part)
  int occasions = 0;            // the reversals (passes) in both parts
  int covered = 0;              // of them with a burst within kEventLock (a pass in and out of a catch: two)
  double size = 0.0;            // RMS of the residual on `joint` over the bursts' stretches [N m]
  double share = 0.0;           // of the joint's mean square left in both parts
};

// The recurring events of the residual left after the causes (`left`, stacked, one per part) on
// the two parts. A joint's bursts are locked to a joint's reversals when at least kEventLockedShare
// of them lie within kEventLock of one, or to its position when as many find it within
// kEventPositionLock of their median there; and then only when at least kEventCoverage of those
// reversals (or passes through the position) have a locked burst within kEventLock: a coincidence
// of a few isolated bursts with a frequent motion fails the second rule, bursts spread over the
// log the first.
std::vector<MotionEvent> find_motion_events(const std::array<const Part*, 2>& parts,
                                            const std::array<const Eigen::VectorXd*, 2>& left);

// Whether a burst of `event` lies in [start, end] [s] of the held-out part (`heldout`) or the training part.
bool has_burst_within(const MotionEvent& event, bool heldout, double start, double end);

}  // namespace csp::gap
