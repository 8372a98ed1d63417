// The libfranka-shaped API (rt/franka): reflexes through purpose-built controllers, lost commands,
// failing controllers, the Model against the core, and the control loop's timing contract.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "csp/dynamics/algorithms.hpp"
#include "csp/franka_access.hpp"
#include "csp/rt/csv_log.hpp"
#include "franka/model.h"
#include "franka/robot.h"
#include "reflex_trips.hpp"

namespace {

using csp::rt::Error;

using Robot = csp::franka_access::LockstepRobot;

csp::rt::ErrorSet set_of(const franka::Errors& errors) { return csp::rt::ErrorSet(errors); }

// The default scenario without its scripted push.
csp::rt::Scenario quiet_scenario() {
  csp::rt::Scenario s = csp::rt::load_scenario(csp::rt::default_scenario_path());
  s.emulator.external_wrenches.clear();
  return s;
}

csp::rt::ErrorSet only(Error error) {
  csp::rt::ErrorSet e;
  e.set(error);
  return e;
}

// Holds the pose with zero torque for `cycles` cycles, then finishes.
std::function<franka::Torques(const franka::RobotState&, franka::Duration)> zero_torque_for(int cycles) {
  return [cycles, n = 0](const franka::RobotState&, franka::Duration) mutable {
    franka::Torques tau({0, 0, 0, 0, 0, 0, 0});
    return ++n >= cycles ? franka::MotionFinished(tau) : tau;
  };
}

TEST(FrankaReflexes, EachTripReportsExactlyItsErrorAndRecovers) {
  const csp::rt::Scenario base = quiet_scenario();
  for (const csp_examples::ReflexTrip& trip : csp_examples::reflex_trips()) {
    SCOPED_TRACE(csp::rt::error_name(trip.error));
    csp::rt::Scenario scenario = base;
    if (trip.prepare) trip.prepare(scenario);
    Robot robot(scenario);
    std::string what;
    try {
      trip.run(robot);
    } catch (const franka::ControlException& e) {
      what = e.what();
      EXPECT_FALSE(e.log.empty());
      EXPECT_EQ(e.log.back().state.robot_mode, franka::RobotMode::kReflex);
    }
    const franka::RobotState& state = robot.emulator().state();
    EXPECT_EQ(state.robot_mode, franka::RobotMode::kReflex);
    EXPECT_NE(what.find(csp::rt::error_name(trip.error)), std::string::npos) << what;
    if (trip.error == Error::joint_position_motion_generator_start_pose_invalid) {
      // The core also flags the same cycle's velocity, acceleration and jerk (see the report).
      EXPECT_TRUE(csp::rt::has(state.current_errors, trip.error));
      EXPECT_TRUE(csp::rt::has(state.last_motion_errors, trip.error));
    } else {
      // libfranka's message: the errors as a JSON array, then the success rate before the reflex.
      EXPECT_EQ(what.rfind("libfranka: Move command aborted: motion aborted by reflex! [\"" +
                               std::string(csp::rt::error_name(trip.error)) + "\"]\ncontrol_command_success_rate: ",
                           0),
                0u)
          << what;
      EXPECT_EQ(set_of(state.current_errors), only(trip.error));
      EXPECT_EQ(set_of(state.last_motion_errors), only(trip.error));
    }
    // A motion cannot start in Reflex; after recovery it can.
    EXPECT_THROW(robot.control(zero_torque_for(10)), franka::ControlException);
    csp_examples::wait_until_settled(robot);
    robot.automaticErrorRecovery();
    EXPECT_FALSE(robot.emulator().state().current_errors);
    EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
    // Past a joint limit a new motion starts but ends at once (the arm must be guided back). The
    // pushes keep turning joint 7 while the robot brakes, up to its limit (see the report).
    const csp::JointLimits& limits = robot.emulator().plant_model().parameters().joint_limits;
    const csp::Vector7 q(robot.emulator().state().q.data());
    const bool past_a_limit = (q.array() > limits.q_max.array()).any() || (q.array() < limits.q_min.array()).any();
    if (!past_a_limit) {
      EXPECT_NO_THROW(robot.control(zero_torque_for(10)));
    }
  }
}

// The robot tolerates 19 lost commands in a row and stops at the 20th.
TEST(FrankaReflexes, CommunicationViolationAfterExactly20LostCommands) {
  for (int lost : {19, 20}) {
    csp::rt::Scenario scenario = quiet_scenario();
    scenario.command_faults.bursts = {{0.1, lost}};
    Robot robot(scenario);
    if (lost == 19) {
      EXPECT_NO_THROW(robot.control(zero_torque_for(300)));
      EXPECT_EQ(robot.lastTiming().lost_commands, 19u);
      EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
    } else {
      EXPECT_THROW(robot.control(zero_torque_for(300)), franka::ControlException);
      EXPECT_EQ(set_of(robot.emulator().state().current_errors), only(Error::communication_constraints_violation));
      EXPECT_EQ(robot.lastTiming().lost_commands, 20u);
    }
  }
}

// A NaN command: libfranka's std::invalid_argument, robot in Reflex, and the observer's log is complete.
TEST(FrankaReflexes, NanCommandEndsInReflexWithCompleteLog) {
  Robot robot(quiet_scenario());
  const std::string path = ::testing::TempDir() + "franka_nan.csv";
  uint64_t rows = 0;
  {
    csp::rt::CsvLog log(path);
    robot.setCycleObserver([&](const franka::RobotState& s, const csp::rt::CycleInfo& c) { log.write(s, c); });
    EXPECT_THROW(robot.control(csp_examples::nan_controller()), std::invalid_argument);
    rows = log.rows();
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kReflex);
  // 100 commanded cycles (0 .. 99 ms), then the abort.
  EXPECT_EQ(rows, 101u);
  std::ifstream in(path);
  std::string line;
  uint64_t lines = 0;
  while (std::getline(in, line)) ++lines;
  EXPECT_EQ(lines, rows + 1);   // header
}

TEST(FrankaReflexes, ThrowingControllerPropagatesItsExceptionAndRobotIsInReflex) {
  Robot robot(quiet_scenario());
  int calls = 0;
  try {
    robot.control([&](const franka::RobotState&, franka::Duration) -> franka::Torques {
      if (++calls == 50) throw std::runtime_error("controller bug");
      return franka::Torques({0, 0, 0, 0, 0, 0, 0});
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "controller bug");
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kReflex);
}

TEST(FrankaControl, PeriodAndTimeAdvanceOneMillisecondAndMotionFinishedEndsInIdle) {
  Robot robot(quiet_scenario());
  std::vector<uint64_t> periods, times;
  robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::Torques {
    periods.push_back(period.toMSec());
    times.push_back(state.time.toMSec());
    franka::Torques tau({0, 0, 0, 0, 0, 0, 0});
    return periods.size() == 20 ? franka::MotionFinished(tau) : tau;
  });
  ASSERT_EQ(periods.size(), 20u);
  EXPECT_EQ(periods[0], 0u);
  for (std::size_t i = 1; i < periods.size(); ++i) {
    EXPECT_EQ(periods[i], 1u);
    EXPECT_EQ(times[i], times[i - 1] + 1);
  }
  EXPECT_EQ(robot.emulator().state().robot_mode, franka::RobotMode::kIdle);
  const uint64_t before = robot.readOnce().time.toMSec();
  EXPECT_EQ(robot.readOnce().time.toMSec(), before + 1);
}

TEST(FrankaControl, InitializerListOfWrongSizeThrows) {
  EXPECT_THROW(franka::Torques({1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(franka::JointPositions({1.0}), std::invalid_argument);
  EXPECT_THROW(franka::JointVelocities({1, 2, 3, 4, 5, 6, 7, 8}), std::invalid_argument);
}

// franka::Model equals the core's algorithms on the robot's internal model.
TEST(FrankaModel, MatchesTheCoreOnTheInternalModel) {
  Robot robot(quiet_scenario());
  const franka::Model model = robot.loadModel();
  franka::RobotState state = robot.readOnce();
  state.q = {{0.3, -0.5, 0.2, -2.0, 0.4, 1.8, -0.6}};
  state.dq = {{0.2, -0.1, 0.3, 0.4, -0.5, 0.2, 0.6}};
  const csp::Model& core = robot.emulator().internal_model();
  csp::Data data;
  const csp::Vector7 q(state.q.data()), dq(state.dq.data());
  csp::forward_kinematics(core, data, q);

  const auto ee_pose = model.pose(franka::Frame::kEndEffector, state);
  const Eigen::Matrix4d expected_pose = csp::frame_pose(data, csp::Frame::kEndEffector).matrix();
  for (int k = 0; k < 16; ++k) EXPECT_NEAR(ee_pose[k], expected_pose(k % 4, k / 4), 1e-12);   // column-major
  csp::Matrix6x7 J;
  csp::zero_jacobian(data, csp::Frame::kEndEffector, J);
  const auto jacobian = model.zeroJacobian(franka::Frame::kEndEffector, state);
  const Eigen::Map<const csp::Matrix6x7> jacobian_map(jacobian.data());
  EXPECT_LT((jacobian_map - J).cwiseAbs().maxCoeff(), 1e-12);
  // Column j is joint j's twist: joint 1 spins about the base z axis.
  EXPECT_NEAR(jacobian[5], 1.0, 1e-12);
  csp::body_jacobian(data, csp::Frame::kFlange, J);
  const auto body = model.bodyJacobian(franka::Frame::kFlange, state);
  EXPECT_LT((Eigen::Map<const csp::Matrix6x7>(body.data()) - J).cwiseAbs().maxCoeff(), 1e-12);

  csp::crba(core, data, q);
  const auto mass = model.mass(state);
  const Eigen::Map<const csp::Matrix7> mass_map(mass.data());
  EXPECT_LT((mass_map - data.mass_matrix).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((mass_map - mass_map.transpose()).cwiseAbs().maxCoeff(), 1e-12);

  csp::Vector7 g, c;
  csp::gravity_torque(core, data, q, g);
  csp::coriolis_torque(core, data, q, dq, c);
  const auto gravity = model.gravity(state), coriolis = model.coriolis(state);
  EXPECT_LT((csp::Vector7(gravity.data()) - g).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((csp::Vector7(coriolis.data()) - c).cwiseAbs().maxCoeff(), 1e-12);

  // The explicit-parameter overloads honour another load and another F_T_EE.
  csp::RigidBodyInertia extra{1.5, csp::Vector3(0.0, 0.02, 0.1), csp::Matrix3::Identity() * 1e-3};
  const csp::RigidBodyInertia total = csp::combine(core.total_flange_load(), extra);
  const csp::Model loaded = csp::with_load(core, extra);
  csp::gravity_torque(loaded, data, q, g);
  std::array<double, 3> com{};
  csp::Vector3::Map(com.data()) = total.com;
  const auto gravity_loaded = model.gravity(state.q, total.mass, com);
  EXPECT_LT((csp::Vector7(gravity_loaded.data()) - g).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((csp::Vector7(gravity_loaded.data()) - csp::Vector7(gravity.data())).norm(), 0.5);

  std::array<double, 16> F_T_EE = state.F_T_EE;
  F_T_EE[14] += 0.1;   // 10 cm further along the flange z axis
  const auto moved = model.pose(franka::Frame::kEndEffector, state.q, F_T_EE, state.EE_T_K);
  const csp::Vector3 shift = Eigen::Map<const Eigen::Matrix4d>(moved.data()).col(3).head<3>() -
                             Eigen::Map<const Eigen::Matrix4d>(ee_pose.data()).col(3).head<3>();
  const csp::Vector3 flange_z = csp::frame_pose(data, csp::Frame::kFlange).rotation.col(2);
  EXPECT_LT((shift - 0.1 * flange_z).norm(), 1e-12);
}

TEST(FrankaModel, SetLoadChangesStateAndGravity) {
  Robot robot(quiet_scenario());
  const franka::RobotState before = robot.readOnce();
  const auto gravity_before = robot.loadModel().gravity(before);
  robot.setLoad(2.0, {{0.0, 0.0, 0.05}}, {{1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3}});
  const franka::RobotState after = robot.readOnce();
  EXPECT_DOUBLE_EQ(after.m_load, 2.0);
  EXPECT_DOUBLE_EQ(after.m_total, before.m_ee + 2.0);
  const auto gravity_after = robot.loadModel().gravity(after);
  EXPECT_GT(std::abs(gravity_after[1] - gravity_before[1]), 0.5);
}

}  // namespace
