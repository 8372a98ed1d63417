#include "reflex_trips.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csp_examples {
namespace {

using csp::rt::Error;
using franka::Duration;
using franka::RobotState;

constexpr int kJoint2 = 1, kJoint7 = 6;
constexpr double kGiveUpAfter = 5.0;   // [s] a trip that has not tripped by then ends its motion
constexpr double kPushEnd = 1.2;       // [s] robot time

// Gains of libfranka's joint impedance example [N m/rad], [N m s/rad].
constexpr std::array<double, 7> kStiffness{{600, 600, 600, 600, 250, 150, 50}};
constexpr std::array<double, 7> kDamping{{50, 50, 50, 20, 20, 20, 10}};

// Collision thresholds high enough not to trip [N m], [N, N m].
constexpr std::array<double, 7> kHighTorque{{100, 100, 100, 100, 100, 100, 100}};
constexpr std::array<double, 6> kHighForce{{100, 100, 100, 100, 100, 100}};
// libfranka's examples' defaults (setDefaultBehavior: the nominal values).
constexpr std::array<double, 7> kDefaultTorque{{10, 10, 10, 10, 10, 10, 10}};
constexpr std::array<double, 6> kDefaultForce{{10, 10, 10, 10, 10, 10}};

// A velocity that ramps from rest to `target` with bounded acceleration and jerk; one step per cycle.
struct SmoothRamp {
  double target, acceleration, jerk;
  double a = 0.0, v = 0.0, x = 0.0;

  void step(double dt) {
    const double direction = target < 0.0 ? -1.0 : 1.0;
    a = std::min(acceleration, a + jerk * dt);
    v = std::min(std::abs(target), std::abs(v) + a * dt) * direction;
    if (std::abs(v) == std::abs(target)) a = 0.0;
    x += v * dt;
  }
};

// Torque control: joint impedance around the start pose, joints in `moving` following their ramps.
// The torques start at zero (the first state is the target), so they have no discontinuity.
std::function<franka::Torques(const RobotState&, Duration)> hold_and_move(std::vector<std::pair<int, SmoothRamp>> moving) {
  std::array<double, 7> q_start{};
  double time = 0.0;
  return [=](const RobotState& state, Duration period) mutable -> franka::Torques {
    if (period.toMSec() == 0) q_start = state.q;
    time += period.toSec();
    std::array<double, 7> q_d = q_start, dq_d{};
    for (auto& [joint, ramp] : moving) {
      if (period.toMSec() > 0) ramp.step(period.toSec());
      q_d[joint] += ramp.x;
      dq_d[joint] = ramp.v;
    }
    std::array<double, 7> tau{};
    for (std::size_t i = 0; i < 7; ++i) tau[i] = kStiffness[i] * (q_d[i] - state.q[i]) + kDamping[i] * (dq_d[i] - state.dq[i]);
    return time > kGiveUpAfter ? franka::MotionFinished(franka::Torques(tau)) : franka::Torques(tau);
  };
}

auto hold() { return hold_and_move({}); }

// Joint velocity motion generator: joint 7 follows `velocity(time)`.
void run_joint7_velocity(franka::Robot& robot, std::function<double(double)> velocity) {
  double time = 0.0;
  robot.control(
      [&](const RobotState&, Duration period) -> franka::JointVelocities {
        time += period.toSec();
        franka::JointVelocities command({0, 0, 0, 0, 0, 0, 0});
        command.dq[kJoint7] = velocity(time);
        return time > kGiveUpAfter ? franka::MotionFinished(command) : command;
      },
      franka::ControllerMode::kJointImpedance, false, franka::kMaxCutoffFrequency);
}

// Joint position motion generator: starts from the robot's desired pose, joint 7 offset by `offset(time)`.
void run_joint7_position(franka::Robot& robot, std::function<double(double)> offset) {
  double time = 0.0;
  std::array<double, 7> q_start{};
  robot.control(
      [&](const RobotState& state, Duration period) -> franka::JointPositions {
        if (period.toMSec() == 0) q_start = state.q_d;
        time += period.toSec();
        franka::JointPositions command(q_start);
        command.q[kJoint7] += offset(time);
        return time > kGiveUpAfter ? franka::MotionFinished(command) : command;
      },
      franka::ControllerMode::kJointImpedance, false, franka::kMaxCutoffFrequency);
}

// Integrates a SmoothRamp once per new time value: the velocity (or position) at `time`.
std::function<double(double)> ramp_profile(SmoothRamp ramp, bool position) {
  return [ramp, position, last = 0.0](double time) mutable {
    if (time > last) ramp.step(time - last);
    last = time;
    return position ? ramp.x : ramp.v;
  };
}

// A push on the hand (link 7) scripted by the scenario: ramps in over 0.5 s from 0.05 s, then
// straight out again; it is over at kPushEnd.
std::function<void(csp::rt::Scenario&)> push(const csp::Vector3& force, const csp::Vector3& moment) {
  return [=](csp::rt::Scenario& scenario) {
    csp::rt::ExternalWrench w;
    w.link = 7;
    w.force = force;
    w.moment = moment;
    w.start = 0.05;
    w.end = kPushEnd;
    w.ramp = 0.5;
    scenario.emulator.external_wrenches.push_back(w);
  };
}

// Unfiltered: the robot gets exactly what the controller commands.
void control(franka::Robot& robot, std::function<franka::Torques(const RobotState&, Duration)> controller,
             bool limit_rate = false) {
  robot.control(std::move(controller), limit_rate, franka::kMaxCutoffFrequency);
}

}  // namespace

std::vector<ReflexTrip> reflex_trips() {
  std::vector<ReflexTrip> trips;
  trips.push_back({Error::joint_position_limits_violation,
                   "torque control drives joint 7 at 1 rad/s past its upper limit", {},
                   [](franka::Robot& robot) { control(robot, hold_and_move({{kJoint7, SmoothRamp{1.0, 5.0, 100.0}}})); }});
  trips.push_back({Error::joint_velocity_violation, "torque control spins joint 7 up to 3.5 rad/s (limit 2.61)", {},
                   [](franka::Robot& robot) { control(robot, hold_and_move({{kJoint7, SmoothRamp{3.5, 20.0, 400.0}}})); }});
  trips.push_back({Error::joint_reflex,
                   "someone twists the tool (20 N m about the vertical); joint thresholds 10 N m, Cartesian raised",
                   push(csp::Vector3::Zero(), csp::Vector3(0.0, 0.0, 20.0)),
                   [](franka::Robot& robot) {
                     robot.setCollisionBehavior(kDefaultTorque, kDefaultTorque, kHighForce, kHighForce);
                     control(robot, hold());
                   }});
  trips.push_back({Error::cartesian_reflex,
                   "someone pushes the tool sideways (40 N); Cartesian thresholds 10 N, joint thresholds raised",
                   push(csp::Vector3(40.0, 0.0, 0.0), csp::Vector3::Zero()),
                   [](franka::Robot& robot) {
                     robot.setCollisionBehavior(kHighTorque, kHighTorque, kDefaultForce, kDefaultForce);
                     control(robot, hold());
                   }});
  trips.push_back({Error::joint_position_motion_generator_start_pose_invalid,
                   "a joint position generator whose first command is 10 mrad away from the robot's pose", {},
                   [](franka::Robot& robot) { run_joint7_position(robot, [](double) { return 0.01; }); }});
  trips.push_back({Error::joint_motion_generator_position_limits_violation,
                   "a joint position generator moving joint 7 at 1 rad/s past its lower limit; a soft joint 7 lags behind", {},
                   [](franka::Robot& robot) {
                     robot.setJointImpedance({{3000, 3000, 3000, 2500, 2500, 2000, 100}});
                     run_joint7_position(robot, ramp_profile(SmoothRamp{-1.0, 5.0, 1000.0}, true));
                   }});
  trips.push_back({Error::joint_motion_generator_velocity_limits_violation,
                   "a joint velocity generator accelerating joint 7 smoothly to 3 rad/s (limit 2.61)", {},
                   [](franka::Robot& robot) { run_joint7_velocity(robot, ramp_profile(SmoothRamp{3.0, 10.0, 1000.0}, false)); }});
  trips.push_back({Error::joint_motion_generator_velocity_discontinuity,
                   "a joint velocity generator whose acceleration grows by 5 rad/s^2 per ms past 20 rad/s^2", {},
                   [](franka::Robot& robot) { run_joint7_velocity(robot, ramp_profile(SmoothRamp{3.0, 1e9, 5000.0}, false)); }});
  trips.push_back({Error::joint_motion_generator_acceleration_discontinuity,
                   "a joint velocity generator stepping joint 7's velocity by 0.012 rad/s (a jerk of 12000 rad/s^3)", {},
                   [](franka::Robot& robot) { run_joint7_velocity(robot, [](double t) { return t >= 0.05 ? 0.012 : 0.0; }); }});
  trips.push_back({Error::controller_torque_discontinuity,
                   "torque control adds a 2 N m step on joint 7 after 0.1 s (at most 1 N m per ms)", {},
                   [](franka::Robot& robot) {
                     control(robot, [holding = hold(), time = 0.0](const RobotState& state, Duration period) mutable {
                       time += period.toSec();
                       franka::Torques tau = holding(state, period);
                       if (time > 0.1) tau.tau_J[kJoint7] += 2.0;
                       return tau;
                     });
                   }});
  trips.push_back({Error::communication_constraints_violation,
                   "the network loses 20 commands in a row from 0.1 s (the robot tolerates 19)",
                   [](csp::rt::Scenario& scenario) { scenario.command_faults.bursts = {{0.1, 20}}; },
                   [](franka::Robot& robot) { control(robot, hold()); }});
  trips.push_back({Error::power_limit_violation,
                   "rate-limited torque control swings joints 1, 2 and 4 at 1.8 rad/s at once (over the 80 W power "
                   "limit); collision thresholds raised",
                   {},
                   [](franka::Robot& robot) {
                     robot.setCollisionBehavior(kHighTorque, kHighTorque, kHighForce, kHighForce);
                     const SmoothRamp swing{1.8, 30.0, 300.0};
                     control(robot, hold_and_move({{0, swing}, {kJoint2, swing}, {3, swing}}), true);
                   }});
  trips.push_back({Error::tau_j_range_violation,
                   "a clamp twists the tool ever harder (up to 20 N m) while the arm holds; thresholds raised",
                   push(csp::Vector3::Zero(), csp::Vector3(0.0, 0.0, 20.0)),
                   [](franka::Robot& robot) {
                     robot.setCollisionBehavior(kHighTorque, kHighTorque, kHighForce, kHighForce);
                     control(robot, hold());
                   }});
  return trips;
}

std::function<franka::Torques(const RobotState&, Duration)> nan_controller() {
  return [holding = hold(), time = 0.0](const RobotState& state, Duration period) mutable {
    time += period.toSec();
    franka::Torques tau = holding(state, period);
    if (time >= 0.1) tau.tau_J[0] = std::numeric_limits<double>::quiet_NaN();
    return tau;
  };
}

void wait_until_settled(franka::Robot& robot) {
  robot.read([](const RobotState& state) {
    const bool at_rest = std::all_of(state.dq.begin(), state.dq.end(), [](double v) { return std::abs(v) < 1e-3; });
    return !(at_rest && state.time.toSec() > kPushEnd);
  });
}

}  // namespace csp_examples
