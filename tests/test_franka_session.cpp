// libfranka 0.15's API as its example programs use it, on the emulated robot: the robot's address,
// the external control loop's timing rules (franka/active_control.h), Robot::stop from another
// thread, robot time between calls, Cartesian motion generators and torque with a motion
// generator, the rate limits and filters, logging.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "../rt/franka/src/robot_address.hpp"
#include "csp/franka_access.hpp"
#include "franka/active_control.h"
#include "franka/active_motion_generator.h"
#include "franka/active_torque_control.h"
#include "franka/control_tools.h"
#include "franka/exception.h"
#include "franka/logging/logger.hpp"
#include "franka/lowpass_filter.h"
#include "franka/model.h"
#include "franka/rate_limiting.h"
#include "franka/robot.h"

namespace {

using Move = research_interface::robot::Move;

const std::string kScenarios = std::string(CSP_SOURCE_DIR) + "/configs/scenarios";

csp::rt::Scenario libfranka_panda() { return csp::rt::load_scenario(kScenarios + "/libfranka_panda.yaml"); }

// Robot time moving only inside calls: bit-reproducible.
struct PandaRobot : csp::franka_access::LockstepRobot {
  PandaRobot() : LockstepRobot(libfranka_panda()) {}
};

// libfranka examples' start pose (examples_common: q_goal).
const std::array<double, 7> kStartPose{{0, -M_PI_4, 0, -3 * M_PI_4, 0, M_PI_2, M_PI_4}};

// ---- The robot's address

TEST(FrankaAddress, ScenarioPathHostnameAndEnvironment) {
  using csp::franka_address::scenario_for_address;
  const std::string panda = kScenarios + "/libfranka_panda.yaml", fr3 = kScenarios + "/libfranka_fr3.yaml";
  EXPECT_EQ(scenario_for_address(fr3, nullptr, kScenarios), fr3);                  // a path stays a path
  EXPECT_EQ(scenario_for_address("172.16.0.2", nullptr, kScenarios), panda);       // an IP: the default
  EXPECT_EQ(scenario_for_address("panda.local", "", kScenarios), panda);           // empty variable = unset
  EXPECT_EQ(scenario_for_address("fr3-robot", "libfranka_fr3", kScenarios), fr3);  // a shipped name
  EXPECT_EQ(scenario_for_address("172.16.0.2", fr3.c_str(), kScenarios), fr3);     // a path in the variable
  EXPECT_EQ(scenario_for_address("fe80::1", nullptr, kScenarios), panda);          // IPv6
  EXPECT_THROW(scenario_for_address("", nullptr, kScenarios), std::invalid_argument);
  EXPECT_THROW(scenario_for_address("robot one", nullptr, kScenarios), std::invalid_argument);
  try {
    scenario_for_address("172.16.0.2", "no_such_robot", kScenarios);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("CSP_SCENARIO=`no_such_robot`"), std::string::npos) << e.what();
  }
}

TEST(FrankaAddress, HostnameConnectsToTheLibfrankaScenarioAtTheExamplesStartPose) {
  unsetenv("CSP_SCENARIO");
  franka::Robot robot("172.16.0.2");
  const franka::RobotState state = robot.readOnce();
  EXPECT_EQ(state.robot_mode, franka::RobotMode::kIdle);
  for (std::size_t i = 0; i < 7; ++i) EXPECT_NEAR(state.q[i], kStartPose[i], 0.1) << "joint " << i + 1;
  EXPECT_FALSE(state.current_errors);
  // A scenario file that does not exist: libfranka's NetworkException, naming the address.
  try {
    franka::Robot missing("/nonexistent/robot.yaml");
    FAIL() << "no exception";
  } catch (const franka::NetworkException& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.yaml"), std::string::npos) << e.what();
  }
  EXPECT_THROW(franka::Robot("172.16.0.2", franka::RealtimeConfig::kEnforce, 0), std::invalid_argument);
}

// ---- External control loop

TEST(FrankaExternalLoop, PeriodsOneWritePerReadAndMotionFinished) {
  PandaRobot robot;
  auto control = robot.startJointPositionControl(Move::ControllerMode::kJointImpedance);
  // While the loop runs, nothing else may use the robot.
  EXPECT_THROW(robot.readOnce(), franka::InvalidOperationException);
  EXPECT_THROW(robot.startTorqueControl(), franka::InvalidOperationException);
  // A command answers a state: no write before the first read.
  EXPECT_THROW(control->writeOnce(franka::JointPositions(kStartPose)), franka::InvalidOperationException);
  std::array<double, 7> q0{};
  uint64_t first_time = 0;
  for (int k = 0; k < 300; ++k) {
    const auto [state, period] = control->readOnce();
    if (k == 0) {
      EXPECT_EQ(period.toMSec(), 0u);
      q0 = state.q_d;
      first_time = state.time.toMSec();
    } else {
      EXPECT_EQ(period.toMSec(), 1u);
      EXPECT_EQ(state.time.toMSec(), first_time + static_cast<uint64_t>(k));
    }
    franka::JointPositions q(q0);
    q.q[6] += 0.05 * (1 - std::cos(M_PI * k / 299.0)) / 2;   // rest to rest
    if (k == 299) q.motion_finished = true;
    control->writeOnce(q);
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  EXPECT_NEAR(robot.emulator().state().q[6], q0[6] + 0.05, 2e-3);   // Idle: q_d is where the arm is
  EXPECT_EQ(robot.lastTiming().lost_commands, 0u);
  // After the motion, the handle is spent; the robot is free again.
  EXPECT_THROW(control->readOnce(), franka::ControlException);
  EXPECT_THROW(control->writeOnce(franka::JointPositions(kStartPose)), franka::ControlException);
  EXPECT_NO_THROW(robot.readOnce());
}

TEST(FrankaExternalLoop, UnansweredStatesAreLostCommandsAndTwentyEndTheMotion) {
  PandaRobot robot;
  auto control = robot.startTorqueControl();
  control->readOnce();
  control->writeOnce(franka::Torques({0, 0, 0, 0, 0, 0, 0}));
  // One state read and not answered: its cycle ran without a command (counted lost); the period
  // is still the robot time since the previous read, as libfranka computes it.
  control->readOnce();
  const auto [state, period] = control->readOnce();
  EXPECT_EQ(period.toMSec(), 1u);
  control->writeOnce(franka::Torques({0, 0, 0, 0, 0, 0, 0}));
  // 20 states in a row without an answer: communication_constraints_violation at the next read.
  std::string what;
  try {
    for (int k = 0; k < 25; ++k) control->readOnce();
  } catch (const franka::ControlException& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("communication_constraints_violation"), std::string::npos) << what;
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kReflex);
  EXPECT_EQ(robot.lastTiming().lost_commands, 21u);   // 1 + 20
}

TEST(FrankaExternalLoop, WriteOnceRulesOfTheControllerMode) {
  PandaRobot robot;
  {
    auto control = robot.startJointVelocityControl(Move::ControllerMode::kJointImpedance);
    control->readOnce();
    // The wrong kind of command, and torques without kExternalController: ControlException.
    EXPECT_THROW(control->writeOnce(franka::Torques({0, 0, 0, 0, 0, 0, 0})), franka::ControlException);
    EXPECT_THROW(control->writeOnce(franka::JointVelocities({0, 0, 0, 0, 0, 0, 0}),
                                    franka::Torques({0, 0, 0, 0, 0, 0, 0})),
                 franka::ControlException);
    // libfranka's check of the values: std::invalid_argument, the state stays unanswered.
    EXPECT_THROW(control->writeOnce(franka::JointVelocities({NAN, 0, 0, 0, 0, 0, 0})), std::invalid_argument);
    control->writeOnce(franka::JointVelocities({0, 0, 0, 0, 0, 0, 0}));
    // Destroyed unfinished: the motion stops (libfranka's cancelMotion) and the robot is Idle.
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  auto control = robot.startJointPositionControl(Move::ControllerMode::kExternalController);
  const franka::RobotState state = control->readOnce().first;
  EXPECT_THROW(control->writeOnce(franka::JointPositions(state.q_d)), franka::ControlException);   // torques missing
  control->writeOnce(franka::JointPositions(state.q_d), franka::Torques({0, 0, 0, 0, 0, 0, 0}));
}

// ---- Robot::stop from another thread

TEST(FrankaStop, StopFromAnotherThreadPreemptsControl) {
  PandaRobot robot;
  std::atomic<int> cycles{0};
  std::thread stopper([&] {
    while (cycles.load() < 100) std::this_thread::yield();
    robot.stop();
  });
  std::string what;
  try {
    robot.control([&](const franka::RobotState&, franka::Duration) {
      ++cycles;
      return franka::Torques({0, 0, 0, 0, 0, 0, 0});
    });
  } catch (const franka::ControlException& e) {
    what = e.what();
  }
  stopper.join();
  EXPECT_EQ(what, "libfranka: Move command preempted!");
  EXPECT_GE(cycles.load(), 100);
  // Stopped, not a reflex: the next motion starts without error recovery.
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  EXPECT_NO_THROW(robot.control([](const franka::RobotState&, franka::Duration) {
    return franka::MotionFinished(franka::Torques({0, 0, 0, 0, 0, 0, 0}));
  }));
}

TEST(FrankaStop, StopEndsTheExternalLoopAtItsNextRead) {
  PandaRobot robot;
  auto control = robot.startTorqueControl();
  control->readOnce();
  robot.stop();
  control->writeOnce(franka::Torques({0, 0, 0, 0, 0, 0, 0}));
  try {
    control->readOnce();
    FAIL() << "no exception";
  } catch (const franka::ControlException& e) {
    EXPECT_STREQ(e.what(), "libfranka: Move command preempted!");
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
}

// ---- Robot time between calls

TEST(FrankaIdleTime, RobotTimeRunsWhileTheProgramIsOutsideACall) {
  csp::franka_access::EmulatedRobot robot(libfranka_panda());   // idle time runs (the default)
  const uint64_t t0 = robot.readOnce().time.toMSec();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const uint64_t t1 = robot.readOnce().time.toMSec();
  EXPECT_GE(t1 - t0, 200u);
  EXPECT_LT(t1 - t0, 1000u);   // a loaded machine may add some, not seconds
  // A push scripted at 0.3-0.5 s is over for a program that comes back at 0.8 s: a retry does not
  // meet it again.
  csp::rt::Scenario pushed = libfranka_panda();
  csp::rt::ExternalWrench push;
  push.link = 7;
  push.force = csp::Vector3(0, 30, 0);
  push.start = 0.3;
  push.end = 0.5;
  push.ramp = 0.05;
  pushed.emulator.external_wrenches.push_back(push);
  csp::franka_access::EmulatedRobot later(pushed);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_GE(later.readOnce().time.toSec(), 0.8);
  EXPECT_NO_THROW(later.control([n = 0](const franka::RobotState&, franka::Duration) mutable {
    franka::Torques zero({0, 0, 0, 0, 0, 0, 0});
    return ++n > 200 ? franka::MotionFinished(zero) : zero;
  }));
}

// ---- Cartesian motion generators, Cartesian impedance, torque with a motion generator

// libfranka's generate_cartesian_pose_motion: x and z on a quarter circle of radius 0.3 m... here
// 5 cm along x and back in 2 s, rest to rest; the end effector ends where the pose says.
TEST(FrankaCartesian, PoseMotionTracksTheCommandedPose) {
  for (auto mode : {franka::ControllerMode::kJointImpedance, franka::ControllerMode::kCartesianImpedance}) {
    PandaRobot robot;
    std::array<double, 16> start{};
    double time = 0.0;
    robot.control(
        [&](const franka::RobotState& state, franka::Duration period) -> franka::CartesianPose {
          time += period.toSec();
          if (time == 0.0) start = state.O_T_EE_c;
          std::array<double, 16> pose = start;
          pose[12] += 0.05 * (1 - std::cos(M_PI * time / 2.0)) / 2;
          return time >= 2.0 ? franka::MotionFinished(franka::CartesianPose(pose)) : franka::CartesianPose(pose);
        },
        mode);
    EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
    for (int k = 0; k < 300; ++k) robot.readOnce();   // settle
    EXPECT_NEAR(robot.emulator().state().O_T_EE[12], start[12] + 0.05, 2e-3);
  }
}

TEST(FrankaCartesian, VelocityMotionWithElbowAndTorqueWithMotionGenerator) {
  PandaRobot robot;
  robot.setCartesianImpedance({{3000, 3000, 3000, 300, 300, 300}});
  EXPECT_THROW(robot.setCartesianImpedance({{5000, 3000, 3000, 300, 300, 300}}), franka::CommandException);
  double time = 0.0;
  std::array<double, 2> elbow{};
  robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::CartesianVelocities {
    time += period.toSec();
    if (time == 0.0) elbow = state.elbow_c;
    const double v = 0.05 * std::sin(M_PI * time);   // one second out and back
    franka::CartesianVelocities out({0.0, v, 0.0, 0.0, 0.0, 0.0}, elbow);
    return time >= 1.0 ? franka::MotionFinished(out) : out;
  });
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  // motion_with_control: the program's PD torques follow the motion generator's q_d.
  time = 0.0;
  std::array<double, 7> q0{};
  robot.control(
      [&](const franka::RobotState& state, franka::Duration) -> franka::Torques {
        std::array<double, 7> tau{};
        for (std::size_t i = 0; i < 7; ++i) tau[i] = 600.0 * (state.q_d[i] - state.q[i]) - 30.0 * state.dq[i];
        return tau;
      },
      [&](const franka::RobotState& state, franka::Duration period) -> franka::JointPositions {
        time += period.toSec();
        if (time == 0.0) q0 = state.q_d;
        franka::JointPositions q(q0);
        q.q[3] += 0.1 * (1 - std::cos(M_PI * time)) / 2;
        return time >= 1.0 ? franka::MotionFinished(q) : q;
      });
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  EXPECT_NEAR(robot.emulator().state().q[3], q0[3] + 0.1, 0.01);
}

// ---- Rate limits, filters, tools

TEST(FrankaRateLimiting, Libfranka015ConstantsAndCartesianLimits) {
  EXPECT_DOUBLE_EQ(franka::kMaxTorqueRate[0], 1000 - 1e-3);
  EXPECT_DOUBLE_EQ(franka::kMaxTranslationalVelocity, 3.0 - 1e-3);
  EXPECT_DOUBLE_EQ(franka::kMaxElbowVelocity, 1.5 - 1e-3);
  // FR3's position-dependent velocity limit: min(2.62, -0.3 + sqrt(12 (2.7501 - q1))) at q1 = 2.7 rad.
  std::array<double, 7> q{};
  q[0] = 2.7;
  EXPECT_NEAR(franka::computeUpperLimitsJointVelocity(q)[0], -0.3 + std::sqrt(12.0 * 0.0501) - 1e-3, 1e-12);
  EXPECT_NEAR(franka::computeLowerLimitsJointVelocity(q)[0], -2.62 + 1e-3, 1e-12);
  // A jump to 1 m/s from rest moves by at most max_jerk dt^2 (jerk-limited first step).
  const std::array<double, 6> zero{};
  const auto twist = franka::limitRate(franka::kMaxTranslationalVelocity, franka::kMaxTranslationalAcceleration,
                                       franka::kMaxTranslationalJerk, franka::kMaxRotationalVelocity,
                                       franka::kMaxRotationalAcceleration, franka::kMaxRotationalJerk,
                                       {{1.0, 0, 0, 0, 0, 2.0}}, zero, zero);
  EXPECT_NEAR(twist[0], franka::kMaxTranslationalJerk * 1e-6, 1e-12);
  EXPECT_NEAR(twist[5], franka::kMaxRotationalJerk * 1e-6, 1e-12);
  // A pose 1 cm away from rest: the limited pose moves as little, is homogeneous, and on the way.
  std::array<double, 16> last{{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.3, 0, 0.5, 1}};
  std::array<double, 16> target = last;
  target[12] += 0.01;
  const auto pose = franka::limitRate(franka::kMaxTranslationalVelocity, franka::kMaxTranslationalAcceleration,
                                      franka::kMaxTranslationalJerk, franka::kMaxRotationalVelocity,
                                      franka::kMaxRotationalAcceleration, franka::kMaxRotationalJerk, target, last,
                                      zero, zero);
  EXPECT_TRUE(franka::isHomogeneousTransformation(pose));
  EXPECT_NEAR(pose[12] - last[12], franka::kMaxTranslationalJerk * 1e-9, 1e-15);
  target[0] = 2.0;   // not a rotation
  EXPECT_THROW(franka::limitRate(1, 1, 1, 1, 1, 1, target, last, zero, zero), std::invalid_argument);
}

TEST(FrankaFilters, CartesianLowpassMovesTheSameFractionInTranslationAndRotation) {
  const double gain = 1e-3 / (1e-3 + 1.0 / (2.0 * M_PI * 100.0));
  std::array<double, 16> last{{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::array<double, 16> y = last;
  Eigen::Map<Eigen::Matrix4d>(y.data()).topLeftCorner<3, 3>() = R;
  y[12] = 0.1;
  const auto f = franka::cartesianLowpassFilter(1e-3, y, last, 100.0);
  EXPECT_NEAR(f[12], gain * 0.1, 1e-15);
  const Eigen::AngleAxisd turned(Eigen::Matrix3d(Eigen::Map<const Eigen::Matrix4d>(f.data()).topLeftCorner<3, 3>()));
  EXPECT_NEAR(turned.angle(), gain * 0.4, 1e-12);
  EXPECT_NEAR(franka::lowpassFilter(1e-3, 1.0, 0.0, 100.0), gain, 1e-15);
  EXPECT_THROW(franka::cartesianLowpassFilter(1e-3, y, last, -1.0), std::invalid_argument);
}

TEST(FrankaTools, ChecksOfCommands) {
  EXPECT_THROW(franka::checkFinite(std::array<double, 3>{{0, NAN, 0}}), std::invalid_argument);
  EXPECT_THROW(franka::checkElbow({{0.0, 0.5}}), std::invalid_argument);
  EXPECT_NO_THROW(franka::checkElbow({{0.0, -1.0}}));
  EXPECT_THROW(franka::checkMatrix({{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 2}}), std::invalid_argument);
  EXPECT_FALSE(franka::CartesianPose(std::array<double, 16>{}).hasElbow());
  EXPECT_TRUE(franka::CartesianVelocities({0, 0, 0, 0, 0, 0}, {0.1, 1}).hasElbow());
  EXPECT_THROW(franka::CartesianPose({1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(franka::CartesianVelocities({0, 0, 0, 0, 0, 0}, {1.0}), std::invalid_argument);
}

// ---- Logging

struct Collect : franka::LoggingSinkInterface {
  std::vector<std::string> lines;
  auto getName() const -> std::string override { return "collect"; }
  auto logInfo(const std::string& m) -> void override { lines.push_back("I " + m); }
  auto logWarn(const std::string& m) -> void override { lines.push_back("W " + m); }
  auto logError(const std::string& m) -> void override { lines.push_back("E " + m); }
};

TEST(FrankaLogging, SinksReceiveMessagesUntilRemovedAndLogToCSVHasOneRowPerRecord) {
  auto sink = std::make_shared<Collect>();
  franka::logging::addLogger(sink);
  franka::logging::logInfo(std::string("one"));
  franka::logging::logError(std::string("two"));
  franka::logging::removeLogger("collect");
  franka::logging::logWarn(std::string("three"));
  EXPECT_EQ(sink->lines, (std::vector<std::string>{"I one", "E two"}));
  std::vector<franka::Record> log(3);
  const std::string csv = franka::logToCSV(log);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);
}

}  // namespace
