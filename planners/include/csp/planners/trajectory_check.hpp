// The independent check of a trajectory (`csp plan check`, and every plan before it is written):
// a joint log (docs/joint-log.md) judged sample by sample, at its own rate, against the robot's
// limits and the scene, as the robot would judge it while running it.
//
// - position against [q_min, q_max]; velocity (the file's dq) against dq_lower(q)..dq_upper(q)
//   (FR3: position-based);
// - acceleration and jerk as the robot's motion generator computes them: backward differences of
//   the commanded velocity, from rest before the first row;
// - the torque the motion needs (RNEA of the model, i.e. the robot with the scene's tool, plus its
//   friction; the file's ddq when it has one, else the difference above), its rate, and the power
//   sum of positive joint powers tau dq, the emulator's power_limit_violation check;
// - the tool (TCP) speed;
// - the clearance per obstacle class at every sample (ClearanceChecker), and between samples the
//   certified motion check, so that nothing between two samples can collide unseen.
#pragma once

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"

namespace csp::planners {

struct CheckOptions {
  // [W]; <= 0: the robot file's (JointLimits::power_max, kDefaultPowerMax unless the file gives one).
  double power_limit = 0.0;
  // TCP speed [m/s]; <= 0: the robot file's Cartesian translation limit.
  double tool_speed_limit = 0.0;
  // false: every pair exactly at every sample (the naive baseline of bench/bench_plan_check.cpp).
  bool broad_phase = true;
};

// A trajectory file that is not a trajectory: a position step the velocity limit cannot explain.
class TrajectoryInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One violated limit, at its first violating sample.
struct CheckFailure {
  std::string kind;     // position, velocity, acceleration, jerk, torque, torque_rate, power, tool_speed, clearance, motion
  int joint = 0;        // 1..7 for joint limits, 0 otherwise
  double t = 0.0;       // [s], the file's time
  int row = 0;          // 0-based data row
  double value = 0.0;   // the violating value (clearance: the signed clearance)
  double limit = 0.0;
  std::string detail;   // clearance: the pair and class
};

// Per joint: the largest fraction of each limit used and when (position: of the distance from the
// middle of the range to a limit).
struct JointUsage {
  double position = 0.0, velocity = 0.0, acceleration = 0.0, jerk = 0.0, torque = 0.0, torque_rate = 0.0;
  double position_margin = 0.0;   // smallest distance to a position limit [rad]
  double t_velocity = 0.0, t_acceleration = 0.0, t_jerk = 0.0, t_torque = 0.0;
};

// The tightest pair of one obstacle class over the whole trajectory.
struct ClassClearance {
  std::string obstacle_class;
  double clearance = 0.0;   // distance - required [m]; +inf when the class has no pair
  double distance = 0.0;
  double t = 0.0;
  std::string moving, other;
};

struct TrajectoryCheck {
  bool passed = true;
  std::vector<CheckFailure> failures;   // the first violation of each kind (and joint / class)
  std::size_t samples = 0;
  double duration = 0.0, rate_hz = 0.0;
  std::vector<JointUsage> joints;       // 7
  double peak_power = 0.0, t_peak_power = 0.0, power_limit = 0.0;
  double peak_tool_speed = 0.0, t_peak_tool_speed = 0.0, tool_speed_limit = 0.0;
  std::vector<ClassClearance> clearance;   // per class of the scene, "self" included
  std::size_t uncertified_motions = 0;     // sample-to-sample motions the certified check refused
  // The smallest clearance over the samples (dense), and the smallest certified one over the
  // sample-to-sample motions between valid samples (ClearanceChecker::certified_clearance: what no
  // state between two samples can go below) with the motion's start time; +inf when none.
  double dense_min_clearance = std::numeric_limits<double>::infinity();
  double certified_min_clearance = std::numeric_limits<double>::infinity(), t_certified_min = 0.0;
  // Per sample, for figures: time, the smallest clearance over all classes, the TCP position.
  std::vector<double> t, min_clearance;
  std::vector<Vector3> tool_position;
};

// `model`: the robot with the scene's tool (with_tool). Throws TrajectoryInputError naming the
// log's source, line, time and column for a jump: a position step larger than twice what the
// joint's velocity limit allows in that sample (a trajectory a little too fast is a velocity
// failure to report, not a broken file). NaN, missing columns and unordered time are the joint-log
// reader's errors.
TrajectoryCheck check_trajectory(const JointLog& log, const Model& model, const Scene& scene,
                                 const CheckOptions& options = {});

// One line for a failure, e.g. "velocity of joint 4 at t = 3.217 s: 2.31 > 2.175 rad/s".
std::string describe(const CheckFailure& failure);

}  // namespace csp::planners
