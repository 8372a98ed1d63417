#include "csp/planners/profile.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

#include <unsupported/Eigen/Polynomials>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/friction.hpp"

namespace csp::planners {
namespace {

constexpr int kPhases = 1000;              // grid of the stretching checks (per segment)
constexpr int kDynamicRounds = 30;         // rounds of the torque, torque rate and power stretches
constexpr double kLongestSegment = 1e5;    // [s]: a power limit that needs longer is an error

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

// One phase u of a segment q(t) = a + s(t/T) delta, in parts whose dependence on T is known: with
// dq1 = s'(u) delta and ddq1 = s''(u) delta (the motion at T = 1),
//   tau(T)       = g + N / T^2 + f(dq1 / T)                      (Hollerbach 1984: N = M ddq1 + C(dq1) dq1)
//   dtau/dt(T)   = g_u / T + N_u / T^3 + d/dt f(dq1 / T)          (_u: d/du, the phase derivative)
//   power(T)     = sum_j max(0, tau_j(T) dq1_j / T)
// g and N by RNEA, their phase derivatives by central differences in u; the friction part is
// evaluated at each T (a sigmoid or Coulomb law is no power law of T).
struct DynamicPhase {
  Vector7 dq1, dq1_before, dq1_after;   // at u, u - h, u + h (one-sided at the ends)
  double du = 0.0;                      // (u + h) - (u - h)
  Vector7 g, N, g_u, N_u;
};
constexpr double kPhaseStep = 1e-5;      // h of the central differences in u

std::vector<DynamicPhase> dynamic_phases(const Vector7& a, const Vector7& delta, const Model& model, Data& data) {
  std::vector<DynamicPhase> phases(kPhases + 1);
  const auto parts = [&](double u, Vector7& dq1, Vector7& g, Vector7& N) {
    const SepticSample s = septic(u);
    const Vector7 q = a + s.s * delta;
    dq1 = s.ds * delta;
    gravity_torque(model, data, q, g);
    rnea(model, data, q, dq1, Vector7(s.dds * delta), N);
    N -= g;
  };
  for (int k = 0; k <= kPhases; ++k) {
    DynamicPhase& p = phases[static_cast<std::size_t>(k)];
    const double u = static_cast<double>(k) / kPhases;
    Vector7 g_before, g_after, N_before, N_after;
    parts(u, p.dq1, p.g, p.N);
    // One-sided at the ends (septic() clamps u to [0, 1]): there every phase derivative is zero anyway.
    const double lo = std::max(0.0, u - kPhaseStep), hi = std::min(1.0, u + kPhaseStep);
    parts(lo, p.dq1_before, g_before, N_before);
    parts(hi, p.dq1_after, g_after, N_after);
    p.du = hi - lo;
    p.g_u = (g_after - g_before) / p.du;
    p.N_u = (N_after - N_before) / p.du;
  }
  return phases;
}

Vector7 phase_torque(const DynamicPhase& p, const FrictionModel& friction, double T) {
  return p.g + p.N / (T * T) + friction_torque(friction, p.dq1 / T);
}

// The friction's share of the torque rate at duration T (the phase derivative over T).
Vector7 friction_rate(const DynamicPhase& p, const FrictionModel& friction, double T) {
  return (friction_torque(friction, p.dq1_after / T) - friction_torque(friction, p.dq1_before / T)) / (p.du * T);
}

// The largest real root in (0, 1) of h(z) - target, h(z) = c1 z + c2 z^2 + c3 z^3, given h(0) = 0 and
// |h(1)| > |target| with the sign of target (so one exists). If the solver's roots miss it
// (rounding), the bound |h(z)| <= (|c1| + |c2| + |c3|) z on (0, 1] gives a z that is surely enough.
double largest_root_below_one(double c1, double c2, double c3, double target) {
  const double largest = std::max({std::abs(c1), std::abs(c2), std::abs(c3)});
  double root = 0.0;
  if (std::abs(c3) > 1e-12 * largest) {
    const Eigen::PolynomialSolver<double, 3> solver(Eigen::Vector4d(-target, c1, c2, c3));
    for (const std::complex<double>& z : solver.roots())
      if (std::abs(z.imag()) <= 1e-9 && z.real() > 0.0 && z.real() < 1.0) root = std::max(root, z.real());
  } else if (std::abs(c2) > 1e-12 * largest) {   // quadratic: c2 z^2 + c1 z - target = 0
    const double discriminant = c1 * c1 + 4.0 * c2 * target;
    if (discriminant >= 0.0)
      for (const double sign : {-1.0, 1.0}) {
        const double z = (-c1 + sign * std::sqrt(discriminant)) / (2.0 * c2);
        if (z > 0.0 && z < 1.0) root = std::max(root, z);
      }
  } else if (c1 != 0.0) {
    root = target / c1;
  }
  if (!(root > 0.0 && root < 1.0)) root = std::abs(target) / (std::abs(c1) + std::abs(c2) + std::abs(c3));
  return root;
}

// Torque within the share of tau_max: (tau - g) scales with 1/T^2 without friction, so
// k = max sqrt(|tau - g| / (allowed - |g|)); with friction this is approximate (the rounds repeat).
void stretch_for_torque(const std::vector<DynamicPhase>& phases, const Model& model, const TimingLimits& fractions,
                        int index, SegmentTiming& timing) {
  const JointLimits& limits = model.parameters().joint_limits;
  Stretch torque;
  for (const DynamicPhase& p : phases) {
    const Vector7 tau = phase_torque(p, model.parameters().friction, timing.duration);
    for (int j = 0; j < kNumJoints; ++j) {
      const double allowed = fractions.torque * limits.tau_max[j];
      if (std::abs(tau[j]) <= allowed) continue;
      if (std::abs(p.g[j]) >= allowed)
        throw std::invalid_argument("timing: segment " + std::to_string(index) + ": " + joint_text(j) + " needs " +
                                    std::to_string(std::abs(p.g[j])) + " N m against gravity alone, above " +
                                    std::to_string(allowed) + " N m (the torque share of its limit)");
      torque.consider(std::sqrt(std::abs(tau[j] - p.g[j]) / (allowed - std::abs(p.g[j]))), "torque");
    }
  }
  // A hair more than the ratio, so that rounding cannot leave the same sample just above the limit.
  if (torque.binding) timing.duration *= torque.factor * (1.0 + 1e-9), timing.binding = torque.binding;
}

// Torque rate within the share of dtau_max, in closed form per phase and joint: at T' = k T the rate
// is h(z) = a z + c z^2 + b z^3 with z = 1/k, a = g_u/T (gravity), c = the friction part (taken as
// 1/T^2, a viscous law's), b = N_u/T^3 (inertia). For a phase over the limit R, the smallest
// stretch is the largest root z in (0, 1) of h(z) = sign(h(1)) R (as z falls from 1, |h| reaches R
// first with the sign of h(1)): the real roots of a cubic (Eigen's companion-matrix solver).
void stretch_for_torque_rate(const std::vector<DynamicPhase>& phases, const Model& model, const TimingLimits& fractions,
                             SegmentTiming& timing) {
  const JointLimits& limits = model.parameters().joint_limits;
  const double T = timing.duration;
  Stretch rate;
  for (const DynamicPhase& p : phases) {
    const Vector7 friction = friction_rate(p, model.parameters().friction, T);
    for (int j = 0; j < kNumJoints; ++j) {
      const double R = fractions.torque_rate * limits.dtau_max[j];
      const double a = p.g_u[j] / T, b = p.N_u[j] / (T * T * T), c = friction[j];
      const double h1 = a + b + c;
      if (std::abs(h1) <= R) continue;
      rate.consider(1.0 / largest_root_below_one(a, c, b, std::copysign(R, h1)), "torque rate");
    }
  }
  if (rate.binding) timing.duration *= rate.factor * (1.0 + 1e-9), timing.binding = rate.binding;
}

double grid_power(const std::vector<DynamicPhase>& phases, const FrictionModel& friction, double T) {
  double peak = 0.0;
  for (const DynamicPhase& p : phases)
    peak = std::max(peak, phase_torque(p, friction, T).cwiseProduct(p.dq1 / T).cwiseMax(0.0).sum());
  return peak;
}

// Power sum_j max(0, tau_j dq_j) within the limit: its terms scale with 1/T (gravity), 1/T^3
// (inertia) and with the friction law, and the positive parts switch joints in and out, so no
// closed form: a monotone search on T. Doubling until the grid passes, then bisection to 1e-6 of
// T; it assumes that the grid's peak power does not rise again above a passing T (true while
// gravity's power, the slowest-decaying term, is not what binds; a failing T is never returned).
void stretch_for_power(const std::vector<DynamicPhase>& phases, const Model& model, const TimingLimits& fractions,
                       int index, SegmentTiming& timing) {
  const FrictionModel& friction = model.parameters().friction;
  if (grid_power(phases, friction, timing.duration) <= fractions.power) return;
  double low = timing.duration, high = 2.0 * low;
  while (grid_power(phases, friction, high) > fractions.power) {
    if (high > kLongestSegment)
      throw std::invalid_argument("timing: segment " + std::to_string(index) + ": the power stays above " +
                                  std::to_string(fractions.power) + " W even over " + std::to_string(kLongestSegment) + " s");
    low = high, high *= 2.0;
  }
  while (high - low > 1e-6 * high) {
    const double middle = 0.5 * (low + high);
    (grid_power(phases, friction, middle) > fractions.power ? low : high) = middle;
  }
  timing.duration = high;
  timing.binding = "power";
}

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

  // The torque, its rate and the power, from parts computed once per phase (module comment of
  // DynamicPhase): each stage stretches T just enough for its own limit on the grid; a stretch for
  // one can move another (friction is no power law of T), so they repeat until a round leaves T as
  // it is.
  const std::vector<DynamicPhase> phases = dynamic_phases(a, delta, model, data);
  for (int round = 0;; ++round) {
    const double before = timing.duration;
    stretch_for_torque(phases, model, fractions, index, timing);
    stretch_for_torque_rate(phases, model, fractions, timing);
    stretch_for_power(phases, model, fractions, index, timing);
    if (timing.duration == before) break;
    if (round == kDynamicRounds)
      throw std::invalid_argument("timing: segment " + std::to_string(index) + ": the torque, its rate and the power " +
                                  "do not come within their limits by stretching the duration (friction at low speed)");
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
  check_fraction("torque rate", limits.torque_rate, 1.0);
  if (!(limits.power > 0.0) || !std::isfinite(limits.power))
    throw std::invalid_argument("timing: the power limit " + std::to_string(limits.power) + " W is not > 0");
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
