#include "csp/planners/profile.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/friction.hpp"

namespace csp::planners {
namespace {

constexpr int kPhases = 1000;              // grid of the stretching checks (per segment)
constexpr int kTorqueRounds = 30;          // stretches for the torque (each one exact without friction)

std::string joint_text(int j) { return "joint " + std::to_string(j + 1); }

void check_fraction(const char* name, double value, double most) {
  if (!(value > 0.0 && value <= most))
    throw std::invalid_argument(std::string("timing: the ") + name + " limit " + std::to_string(value) +
                                " is outside (0, " + std::to_string(most) + "]");
}

// The velocity bound of joint j at q in the direction of motion (position-based on FR3).
double velocity_bound(const JointLimits& limits, const Vector7& q, int j, double direction) {
  if (!limits.position_based_velocity) return limits.dq_max[j];
  return direction > 0.0 ? limits.dq_upper(q)[j] : -limits.dq_lower(q)[j];
}

struct Stretch {
  double factor = 1.0;
  const char* binding = nullptr;
  void consider(double k, const char* limit) {
    if (k > factor) {
      factor = k;
      binding = limit;
    }
  }
};

// One segment's duration: the peaks, then the grid checks.
SegmentTiming time_segment(const Vector7& a, const Vector7& b, const Model& model, Data& data,
                           const TimingLimits& fractions, int index) {
  const JointLimits& limits = model.parameters().joint_limits;
  const Vector7 delta = b - a;
  if (delta.cwiseAbs().maxCoeff() == 0.0)
    throw std::invalid_argument("timing: waypoints " + std::to_string(index) + " and " + std::to_string(index + 1) +
                                " are equal");
  SegmentTiming timing;
  for (int j = 0; j < kNumJoints; ++j) {
    const double d = std::abs(delta[j]);
    const double candidates[] = {kSepticPeakVelocity * d / (fractions.velocity * limits.dq_max[j]),
                                 std::sqrt(kSepticPeakAcceleration * d / (fractions.acceleration * limits.ddq_max[j])),
                                 std::cbrt(kSepticPeakJerk * d / (fractions.jerk * limits.dddq_max[j]))};
    const char* names[] = {"velocity", "acceleration", "jerk"};
    for (int c = 0; c < 3; ++c)
      if (candidates[c] > timing.duration) {
        timing.duration = candidates[c];
        timing.binding = names[c];
      }
  }

  // Position-based velocity and tool speed: at a fixed phase both scale with 1/T.
  Stretch stretch;
  Matrix6x7 jacobian;
  for (int k = 1; k < kPhases; ++k) {
    const SepticSample s = septic(static_cast<double>(k) / kPhases);
    const Vector7 q = a + s.s * delta;
    const Vector7 dq = s.ds * delta / timing.duration;
    for (int j = 0; j < kNumJoints; ++j) {
      if (dq[j] == 0.0) continue;
      const double bound = fractions.velocity * velocity_bound(limits, q, j, dq[j]);
      if (!(bound > 0.0))
        throw std::invalid_argument("timing: segment " + std::to_string(index) + ": " + joint_text(j) + " at " +
                                    std::to_string(q[j]) + " rad has no velocity left toward its limit (position-based bound)");
      stretch.consider(std::abs(dq[j]) / bound, "velocity");
    }
    forward_kinematics(model, data, q);
    zero_jacobian(data, Frame::kEndEffector, jacobian);
    stretch.consider((jacobian.topRows<3>() * dq).norm() / fractions.tool_speed, "tool speed");
  }
  if (stretch.binding) {
    timing.duration *= stretch.factor;
    timing.binding = stretch.binding;
  }

  // Torque: tau(T) = g + (M s'' + C(s') s') delta / T^2 + friction(s' delta / T).
  for (int round = 0;; ++round) {
    Stretch torque;
    for (int k = 0; k <= kPhases; ++k) {
      const SepticSample s = septic(static_cast<double>(k) / kPhases);
      const Vector7 q = a + s.s * delta;
      const Vector7 dq = s.ds * delta / timing.duration;
      const Vector7 ddq = s.dds * delta / (timing.duration * timing.duration);
      Vector7 tau, g;
      rnea(model, data, q, dq, ddq, tau);
      tau += friction_torque(model.parameters().friction, dq);
      gravity_torque(model, data, q, g);
      for (int j = 0; j < kNumJoints; ++j) {
        const double allowed = fractions.torque * limits.tau_max[j];
        if (std::abs(tau[j]) <= allowed) continue;
        if (std::abs(g[j]) >= allowed)
          throw std::invalid_argument("timing: segment " + std::to_string(index) + ": " + joint_text(j) +
                                      " needs " + std::to_string(std::abs(g[j])) + " N m against gravity alone, above " +
                                      std::to_string(allowed) + " N m (the torque share of its limit)");
        torque.consider(std::sqrt(std::abs(tau[j] - g[j]) / (allowed - std::abs(g[j]))), "torque");
      }
    }
    if (!torque.binding) break;
    if (round == kTorqueRounds)
      throw std::invalid_argument("timing: segment " + std::to_string(index) + ": the torque does not come within " +
                                  "its share by stretching the duration (friction at low speed)");
    // A hair more than the ratio, so that rounding cannot leave the same sample just above the limit.
    timing.duration *= torque.factor * (1.0 + 1e-9);
    timing.binding = torque.binding;
  }
  // Whole milliseconds: the 1 kHz log then samples every waypoint, at rest.
  timing.duration = std::ceil(timing.duration * 1000.0 - 1e-9) / 1000.0;
  return timing;
}

}  // namespace

SepticSample septic(double u) {
  u = std::clamp(u, 0.0, 1.0);
  const double v = 1.0 - u, uv = u * v;
  SepticSample s;
  s.s = u * u * u * u * (35.0 - 84.0 * u + 70.0 * u * u - 20.0 * u * u * u);
  s.ds = 140.0 * uv * uv * uv;
  s.dds = 420.0 * uv * uv * (1.0 - 2.0 * u);
  s.ddds = 840.0 * uv * (1.0 - 5.0 * u + 5.0 * u * u);
  return s;
}

TransferProfile::TransferProfile(std::vector<Vector7> waypoints, std::vector<double> durations)
    : waypoints_(std::move(waypoints)), durations_(std::move(durations)) {
  if (waypoints_.size() < 2 || durations_.size() + 1 != waypoints_.size())
    throw std::invalid_argument("transfer profile: needs n >= 2 waypoints and n - 1 durations, got " +
                                std::to_string(waypoints_.size()) + " and " + std::to_string(durations_.size()));
  start_times_.push_back(0.0);
  for (const double T : durations_) {
    if (!(T > 0.0) || !std::isfinite(T))
      throw std::invalid_argument("transfer profile: a segment duration is " + std::to_string(T) + ", not > 0");
    start_times_.push_back(start_times_.back() + T);
  }
}

JointSample TransferProfile::sample(double t) const {
  t = std::clamp(t, 0.0, duration());
  // The segment whose interval holds t (the last one for t = duration()).
  const auto after = std::upper_bound(start_times_.begin() + 1, start_times_.end() - 1, t);
  const auto i = static_cast<std::size_t>(after - start_times_.begin() - 1);
  const double T = durations_[i];
  const SepticSample s = septic(t >= start_times_[i + 1] ? 1.0 : (t - start_times_[i]) / T);
  const Vector7 delta = waypoints_[i + 1] - waypoints_[i];
  JointSample out;
  out.q = (1.0 - s.s) * waypoints_[i] + s.s * waypoints_[i + 1];   // exactly the waypoints at u = 0 and 1
  out.dq = s.ds / T * delta;
  out.ddq = s.dds / (T * T) * delta;
  out.dddq = s.ddds / (T * T * T) * delta;
  return out;
}

TimedTransfer time_transfer(const std::vector<Vector7>& waypoints, const Model& model, const TimingLimits& limits) {
  check_fraction("velocity", limits.velocity, 1.0);
  check_fraction("acceleration", limits.acceleration, 1.0);
  check_fraction("jerk", limits.jerk, 1.0);
  check_fraction("torque", limits.torque, 1.0);
  if (!(limits.tool_speed > 0.0) || !std::isfinite(limits.tool_speed))
    throw std::invalid_argument("timing: the tool speed limit " + std::to_string(limits.tool_speed) + " m/s is not > 0");
  if (waypoints.size() < 2)
    throw std::invalid_argument("timing: a transfer needs at least 2 waypoints, got " + std::to_string(waypoints.size()));
  Data data;
  std::vector<SegmentTiming> segments;
  std::vector<double> durations;
  for (std::size_t i = 0; i + 1 < waypoints.size(); ++i) {
    segments.push_back(time_segment(waypoints[i], waypoints[i + 1], model, data, limits, static_cast<int>(i)));
    durations.push_back(segments.back().duration);
  }
  return {TransferProfile(waypoints, std::move(durations)), std::move(segments)};
}

JointLog trajectory_log(const TransferProfile& profile, double rate_hz, const Model& model) {
  return sampled_joint_log([&](double t) { return profile.sample(t); }, profile.duration(), rate_hz, model, "transfer");
}

}  // namespace csp::planners
