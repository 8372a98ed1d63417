// Timing in closed form for transfers: rest-to-rest septic segments through the waypoints, stopping
// at each one (docs/planning-transfers.md). Per segment q(t) = q_a + s(t/T) (q_b - q_a) with
//
//   s(u) = 35u^4 - 84u^5 + 70u^6 - 20u^7,   s'(u) = 140 u^3 (1-u)^3,
//   s''(u) = 420 u^2 (1-u)^2 (1-2u),         s'''(u) = 840 u (1-u) (1 - 5u + 5u^2),
//
// zero velocity, acceleration and jerk at both ends (C3 joins: the robot rejects acceleration steps
// and a quintic's would leave jerk steps). Peaks over [0, 1]: |s'| = 35/16 = 2.1875 (u = 1/2),
// |s''| = 84 sqrt(5)/25 = 7.5132 (u = (5 -+ sqrt 5)/10, where u(1-u) = 1/5), |s'''| = 52.5 (u = 1/2).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/planners/fourier.hpp"

namespace csp::planners {

struct SepticSample {
  double s = 0.0, ds = 0.0, dds = 0.0, ddds = 0.0;   // derivatives with respect to u
};
SepticSample septic(double u);   // u clamped to [0, 1]

inline constexpr double kSepticPeakVelocity = 35.0 / 16.0;
inline const double kSepticPeakAcceleration = 84.0 * std::sqrt(5.0) / 25.0;
inline constexpr double kSepticPeakJerk = 52.5;

// The share of each of the robot's limits a transfer may use (planning-notes section 1's margins).
struct TimingLimits {
  double velocity = 0.6;       // of dq_max, or FR3's position-based bounds dq_upper/lower(q)
  double acceleration = 0.5;   // of ddq_max
  double jerk = 0.5;           // of dddq_max
  double torque = 0.7;         // of tau_max, against RNEA (gravity included) plus the model's friction
  double torque_rate = 0.5;    // of dtau_max, the rate of that torque (as jerk: the derivative's share)
  double power = kDefaultPowerMax;   // joint_power, sum_j max(0, tau_j dq_j) [W] (the robot's power_limit_violation bound)
  double tool_speed = 0.25;    // TCP speed [m/s] (assumption: a slow approach near a patient)
};

// Rest-to-rest segments q_i -> q_{i+1} of the given durations; sample() allocates nothing.
class TransferProfile {
 public:
  // waypoints.size() >= 2, durations.size() = waypoints.size() - 1, each > 0 (std::invalid_argument).
  TransferProfile(std::vector<Vector7> waypoints, std::vector<double> durations);

  JointSample sample(double t) const;   // t clamped to [0, duration()]
  double duration() const { return start_times_.back(); }
  const std::vector<Vector7>& waypoints() const { return waypoints_; }
  const std::vector<double>& durations() const { return durations_; }

 private:
  std::vector<Vector7> waypoints_;
  std::vector<double> durations_;
  std::vector<double> start_times_;   // segment i runs over [start_times_[i], start_times_[i + 1]]
};

// What set each segment's duration.
struct SegmentTiming {
  double duration = 0.0;   // [s], a whole number of milliseconds (the log then ends each segment at rest)
  std::string binding;     // "velocity", "acceleration", "jerk", "tool speed", "torque", "torque rate" or "power"
};

struct TimedTransfer {
  TransferProfile profile;
  std::vector<SegmentTiming> segments;
};

// The shortest septic durations within `limits`: per segment T = max_j max(2.1875 |dq_j| / v_j,
// sqrt(7.5132 |dq_j| / a_j), cbrt(52.5 |dq_j| / j_j)) with v, a, j the allowed fractions of dq_max,
// ddq_max, dddq_max; then, on a grid of 1000 phases (the path does not change when T does: velocity
// scales with 1/T, acceleration with 1/T^2), stretched for FR3's position-based velocity bounds
// and the tool speed (exact ratios); for the torque (tau - g scales with 1/T^2 without friction,
// Hollerbach 1984), its rate (gravity's part 1/T, inertia's 1/T^3: the exact smallest stretch per
// phase is the root of a cubic) and the power (mixed terms: a monotone search on T), repeated
// until a round passes, friction included. `model` is the robot with the
// scene's tool (with_tool). Throws std::invalid_argument when no duration can pass: fewer than two
// waypoints, two equal successive waypoints, gravity alone above the torque share, a position-based
// velocity bound of zero on the way, or bad fractions.
TimedTransfer time_transfer(const std::vector<Vector7>& waypoints, const Model& model, const TimingLimits& limits = {});

// The profile sampled at rate_hz as a joint log (sampled_joint_log: q, dq, ddq and the torque the
// motion needs as tau_J).
JointLog trajectory_log(const TransferProfile& profile, double rate_hz, const Model& model);

}  // namespace csp::planners
