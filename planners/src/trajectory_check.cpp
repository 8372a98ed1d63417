#include "csp/planners/trajectory_check.hpp"

#include <cmath>
#include <limits>
#include <set>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/planners/checker.hpp"

namespace csp::planners {
namespace {

// A step beyond this many times what the velocity limit allows in one sample is a discontinuity of
// the file, not a motion (see check_trajectory).
constexpr double kJumpFactor = 2.0;

// Records the first violation of each kind and joint (or class), so that a trajectory that is too
// fast for a whole second reports one failure per joint, not a thousand.
class Failures {
 public:
  void add(CheckFailure failure, const std::string& key) {
    if (seen_.insert(failure.kind + "/" + key).second) list_.push_back(std::move(failure));
  }
  std::vector<CheckFailure> take() { return std::move(list_); }

 private:
  std::set<std::string> seen_;
  std::vector<CheckFailure> list_;
};

// fraction = |value| / limit; a zero limit with a non-zero value is an infinite fraction.
double fraction(double value, double limit) {
  if (limit > 0.0) return std::abs(value) / limit;
  return value == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
}

}  // namespace

std::string describe(const CheckFailure& f) {
  const std::string where = f.joint > 0 ? format(" of joint %d", f.joint) : std::string();
  if (f.kind == "clearance")
    return format("clearance at t = %.3f s: %.4f m below the required (%s)", f.t, -f.value, f.detail.c_str());
  if (f.kind == "motion")
    return format("motion from t = %.3f s to the next sample not certified collision-free (%s)", f.t, f.detail.c_str());
  if (f.kind == "position")
    return format("position%s at t = %.3f s: %.6g rad outside [%s]", where.c_str(), f.t, f.value, f.detail.c_str());
  return format("%s%s at t = %.3f s: |%.6g| > %.6g%s", f.kind.c_str(), where.c_str(), f.t, f.value, f.limit,
                f.detail.empty() ? "" : (" " + f.detail).c_str());
}

TrajectoryCheck check_trajectory(const JointLog& log, const Model& model, const Scene& scene,
                                 const CheckOptions& options) {
  check_joint_log(log);
  JointLimits limits = model.parameters().joint_limits;
  if (options.power_limit > 0.0) limits.power_max = options.power_limit;
  const std::size_t n = log.size();
  TrajectoryCheck result;
  result.samples = n;
  result.duration = log.t.back() - log.t.front();
  result.rate_hz = static_cast<double>(n - 1) / result.duration;
  result.power_limit = limits.power_max;
  result.tool_speed_limit =
      options.tool_speed_limit > 0.0 ? options.tool_speed_limit : model.parameters().cartesian_limits.translation.v_max;
  result.joints.assign(kNumJoints, JointUsage{});
  for (int j = 0; j < kNumJoints; ++j) result.joints[j].position_margin = std::numeric_limits<double>::infinity();

  // A jump first: nothing else means anything in a file that has one.
  for (std::size_t k = 1; k < n; ++k) {
    const double dt = log.t[k] - log.t[k - 1];
    for (int j = 0; j < kNumJoints; ++j) {
      const double step = std::abs(log.q[k][j] - log.q[k - 1][j]);
      const double allowed = limits.dq_max[j] * dt;
      if (step > kJumpFactor * allowed)
        throw TrajectoryInputError(format(
            "%s: line %zu (t = %.6g s), column q%d: a jump of %.6g rad in one sample (%.6g s); the velocity limit "
            "allows %.6g rad (more than %.0fx that is a discontinuity, not a motion)",
            log.source.c_str(), k + 2, log.t[k], j + 1, step, dt, allowed, kJumpFactor));
    }
  }

  ClearanceChecker checker(model, scene);
  const std::vector<std::string>& classes = checker.classes();
  for (const std::string& c : classes)
    result.clearance.push_back({c, std::numeric_limits<double>::infinity(), 0.0, 0.0, "", ""});
  Failures failures;
  Data data;
  Matrix6x7 jacobian;
  Vector7 dq_previous = Vector7::Zero(), ddq_previous = Vector7::Zero(), tau_previous = Vector7::Zero();
  result.t.reserve(n);
  result.min_clearance.reserve(n);
  result.tool_position.reserve(n);

  for (std::size_t k = 0; k < n; ++k) {
    const double t = log.t[k];
    const int row = static_cast<int>(k);
    const double dt = k == 0 ? log.t[1] - log.t[0] : log.t[k] - log.t[k - 1];
    const Vector7& q = log.q[k];
    const Vector7& dq = log.dq[k];
    // As the motion generator: from rest before the first row, backward differences after.
    const Vector7 ddq_difference = (dq - dq_previous) / dt;
    const Vector7 jerk = (ddq_difference - ddq_previous) / dt;
    const Vector7 ddq = log.ddq.empty() ? ddq_difference : log.ddq[k];
    Vector7 tau;
    rnea(model, data, q, dq, ddq, tau);
    tau += friction_torque(model.parameters().friction, dq);
    const Vector7 dtau = k == 0 ? Vector7::Zero() : Vector7((tau - tau_previous) / dt);

    // The robot's per-sample limits, as the emulator judges them (with the round-off allowance of
    // a computed motion); the rates are the motion generator's, judged here alone.
    const double power = joint_power(tau, dq);
    const LimitViolations violated = limit_violations(limits, q, dq, tau, power, kLimitTolerance);
    const Vector7 upper = limits.dq_upper(q), lower = limits.dq_lower(q);
    for (int j = 0; j < kNumJoints; ++j) {
      JointUsage& u = result.joints[j];
      const double middle = 0.5 * (limits.q_max[j] + limits.q_min[j]), half = 0.5 * (limits.q_max[j] - limits.q_min[j]);
      u.position = std::max(u.position, std::abs(q[j] - middle) / half);
      u.position_margin = std::min(u.position_margin, std::min(limits.q_max[j] - q[j], q[j] - limits.q_min[j]));
      if (violated.position[j])
        failures.add({"position", j + 1, t, row, q[j], q[j] > limits.q_max[j] ? limits.q_max[j] : limits.q_min[j],
                      format("%.6g, %.6g", limits.q_min[j], limits.q_max[j])},
                     std::to_string(j));

      const double velocity_limit = dq[j] >= 0.0 ? upper[j] : -lower[j];
      const double v = fraction(dq[j], velocity_limit);
      if (v > u.velocity) u.velocity = v, u.t_velocity = t;
      if (violated.velocity[j]) failures.add({"velocity", j + 1, t, row, dq[j], velocity_limit, "rad/s"}, std::to_string(j));

      auto usage = [&](const char* kind, double value, double limit, bool exceeded, double& peak, double* t_peak,
                       const char* unit) {
        const double f = fraction(value, limit);
        if (f > peak) {
          peak = f;
          if (t_peak) *t_peak = t;
        }
        if (exceeded) failures.add({kind, j + 1, t, row, value, limit, unit}, std::to_string(j));
      };
      auto beyond = [](double value, double limit) { return std::abs(value) > limit + kLimitTolerance; };
      usage("acceleration", ddq_difference[j], limits.ddq_max[j], beyond(ddq_difference[j], limits.ddq_max[j]),
            u.acceleration, &u.t_acceleration, "rad/s^2");
      usage("jerk", jerk[j], limits.dddq_max[j], beyond(jerk[j], limits.dddq_max[j]), u.jerk, &u.t_jerk, "rad/s^3");
      usage("torque", tau[j], limits.tau_max[j], violated.torque[j], u.torque, &u.t_torque, "N m");
      usage("torque_rate", dtau[j], limits.dtau_max[j], beyond(dtau[j], limits.dtau_max[j]), u.torque_rate, nullptr,
            "N m/s");
    }
    if (power > result.peak_power) result.peak_power = power, result.t_peak_power = t;
    if (violated.power) failures.add({"power", 0, t, row, power, limits.power_max, "W"}, "");

    forward_kinematics(model, data, q);
    zero_jacobian(data, Frame::kEndEffector, jacobian);
    const double speed = (jacobian.topRows<3>() * dq).norm();
    if (speed > result.peak_tool_speed) result.peak_tool_speed = speed, result.t_peak_tool_speed = t;
    if (speed > result.tool_speed_limit + kLimitTolerance)
      failures.add({"tool_speed", 0, t, row, speed, result.tool_speed_limit, "m/s"}, "");
    result.tool_position.push_back(frame_pose(data, Frame::kEndEffector).translation);

    const std::vector<StateClearance>& by_class = checker.check_by_class(q, options.broad_phase);
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < by_class.size(); ++c) {
      const StateClearance& s = by_class[c];
      smallest = std::min(smallest, s.clearance);
      ClassClearance& worst = result.clearance[c];
      if (s.clearance < worst.clearance)
        worst = {classes[c], s.clearance, s.distance, t, std::string(s.moving), std::string(s.other)};
      if (s.clearance < 0.0)
        failures.add({"clearance", 0, t, row, s.clearance, 0.0,
                      format("%s vs %s (%s)", std::string(s.moving).c_str(), std::string(s.other).c_str(), classes[c].c_str())},
                     classes[c]);
    }
    // Between two valid samples: certified free, or refused (a collision between them, or a gap
    // too thin to prove free). Into or out of an invalid sample, the sample's failure says it.
    if (k > 0 && smallest >= 0.0 && result.min_clearance.back() >= 0.0) {
      const double certified = checker.certified_clearance(log.q[k - 1], q);
      if (certified < result.certified_min_clearance)
        result.certified_min_clearance = certified, result.t_certified_min = log.t[k - 1];
      if (certified < 0.0 && !checker.motion_is_free(log.q[k - 1], q)) {
        ++result.uncertified_motions;
        failures.add({"motion", 0, log.t[k - 1], row - 1, 0.0, 0.0, format("to t = %.6g s", t)}, "");
      }
    }
    result.dense_min_clearance = std::min(result.dense_min_clearance, smallest);
    result.t.push_back(t);
    result.min_clearance.push_back(smallest);
    dq_previous = dq;
    ddq_previous = ddq_difference;
    tau_previous = tau;
  }
  result.failures = failures.take();
  result.passed = result.failures.empty();
  return result;
}

}  // namespace csp::planners
