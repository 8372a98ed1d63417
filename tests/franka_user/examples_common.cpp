#include "examples_common.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include <franka/exception.h>

const std::array<double, 7> kStartPose{{0.0, -M_PI_4, 0.0, -3.0 * M_PI_4, 0.0, M_PI_2, M_PI_4}};

void setDefaultBehavior(franka::Robot& robot) {
  // Contact (lower) and collision (upper) thresholds alike, higher while the robot accelerates
  // than at constant speed.
  const std::array<double, 7> torque_acceleration{{20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0}};
  const std::array<double, 7> torque_nominal{{10.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0}};
  const std::array<double, 6> force_acceleration{{20.0, 20.0, 20.0, 20.0, 20.0, 20.0}};
  const std::array<double, 6> force_nominal{{10.0, 10.0, 10.0, 10.0, 10.0, 10.0}};
  robot.setCollisionBehavior(torque_acceleration, torque_acceleration, torque_nominal,
                             torque_nominal, force_acceleration, force_acceleration, force_nominal,
                             force_nominal);
  robot.setJointImpedance({{3000.0, 3000.0, 3000.0, 2500.0, 2500.0, 2000.0, 2000.0}});
  robot.setCartesianImpedance({{3000.0, 3000.0, 3000.0, 300.0, 300.0, 300.0}});
}

void setMotionCollisionBehavior(franka::Robot& robot) {
  const std::array<double, 7> torque{{20.0, 20.0, 18.0, 18.0, 16.0, 14.0, 12.0}};
  const std::array<double, 6> force{{20.0, 20.0, 20.0, 25.0, 25.0, 25.0}};
  robot.setCollisionBehavior(torque, torque, torque, torque, force, force, force, force);
}

void setCartesianVelocityBehavior(franka::Robot& robot) {
  robot.setJointImpedance({{3000.0, 3000.0, 3000.0, 2500.0, 2500.0, 2000.0, 2000.0}});
  const std::array<double, 7> torque_contact{{25.0, 25.0, 22.0, 20.0, 19.0, 17.0, 14.0}};
  const std::array<double, 7> torque_collision{{35.0, 35.0, 32.0, 30.0, 29.0, 27.0, 24.0}};
  const std::array<double, 6> force_contact{{30.0, 30.0, 30.0, 25.0, 25.0, 25.0}};
  const std::array<double, 6> force_collision{{40.0, 40.0, 40.0, 35.0, 35.0, 35.0}};
  robot.setCollisionBehavior(torque_contact, torque_collision, torque_contact, torque_collision,
                             force_contact, force_collision, force_contact, force_collision);
}

void moveToStartPose(franka::Robot& robot) {
  MotionGenerator motion_generator(0.5, kStartPose);
  std::cout << "WARNING: This example will move the robot! "
            << "Please make sure to have the user stop button at hand!" << std::endl
            << "Press Enter to continue..." << std::endl;
  std::cin.ignore();
  robot.control(motion_generator);
  std::cout << "Finished moving to initial joint configuration." << std::endl;
}

// The quintic s(tau) on tau in [0, 1] peaks in velocity at tau = 1/2 with s' = 15/8 and in
// acceleration at tau = 1/2 -/+ sqrt(3)/6 with |s''| = 10 sqrt(3)/3. A joint travelling delta in
// time T therefore needs T >= 15/8 |delta| / dq_max and T^2 >= 10 sqrt(3)/3 |delta| / ddq_max.
namespace {
constexpr double kPeakVelocity = 15.0 / 8.0;
const double kPeakAcceleration = 10.0 * std::sqrt(3.0) / 3.0;

double quintic(double tau) {
  return tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
}
}  // namespace

MotionGenerator::MotionGenerator(double speed_factor, const std::array<double, 7> q_goal)
    : q_goal_(q_goal.data()) {
  if (!(speed_factor > 0.0 && speed_factor <= 1.0)) {
    throw std::invalid_argument("MotionGenerator: speed factor " + std::to_string(speed_factor) +
                                " is outside (0, 1]");
  }
  // Bounds kept below the arm's joint velocity (2.175 / 2.61 rad/s) and acceleration
  // (10 rad/s^2) limits, so that a full-speed motion stays clear of them.
  dq_max_ << 2.0, 2.0, 2.0, 2.0, 2.5, 2.5, 2.5;
  ddq_max_.setConstant(5.0);
  dq_max_ *= speed_factor;
  ddq_max_ *= speed_factor;
}

void MotionGenerator::plan(const Vector7d& q_start) {
  q_start_ = q_start;
  const Vector7d distance = (q_goal_ - q_start_).cwiseAbs();
  const Vector7d time_for_velocity = kPeakVelocity * distance.cwiseQuotient(dq_max_);
  const Vector7d time_for_acceleration =
      (kPeakAcceleration * distance.cwiseQuotient(ddq_max_)).cwiseSqrt();
  duration_ = std::max(time_for_velocity.maxCoeff(), time_for_acceleration.maxCoeff());
}

franka::JointPositions MotionGenerator::operator()(const franka::RobotState& robot_state,
                                                   franka::Duration period) {
  time_ += period.toSec();
  if (time_ == 0.0) {  // the first call of a motion comes with a zero period
    plan(Vector7d(robot_state.q.data()));
  }

  const bool finished = time_ >= duration_;
  const double s = finished ? 1.0 : quintic(time_ / duration_);
  std::array<double, 7> q_command{};
  Eigen::Map<Vector7d>(q_command.data()) = q_start_ + s * (q_goal_ - q_start_);

  franka::JointPositions output(q_command);
  output.motion_finished = finished;
  return output;
}

JointPositionWave::JointPositionWave(std::array<double, 7> franka::RobotState::*start_field)
    : start_field_(start_field) {}

franka::JointPositions JointPositionWave::operator()(const franka::RobotState& robot_state,
                                                     franka::Duration period) {
  time_ += period.toSec();
  if (time_ == 0.0) {
    q_initial_ = robot_state.*start_field_;
  }

  const double delta = M_PI / 8.0 * (1.0 - std::cos(2.0 * M_PI / 5.0 * time_));
  std::array<double, 7> q_command = q_initial_;
  for (size_t joint : std::array<size_t, 3>{{3, 4, 6}}) {
    q_command[joint] += delta;
  }

  franka::JointPositions output(q_command);
  if (time_ >= 5.0) {
    std::cout << std::endl << "Finished motion, shutting down example" << std::endl;
    return franka::MotionFinished(output);
  }
  return output;
}

JointVelocityWave::JointVelocityWave(double omega_max,
                                     double leg_time,
                                     std::array<bool, 7> moving_joints)
    : omega_max_(omega_max), leg_time_(leg_time), moving_joints_(moving_joints) {}

franka::JointVelocities JointVelocityWave::operator()(const franka::RobotState& /*robot_state*/,
                                                      franka::Duration period) {
  time_ += period.toSec();

  // The (1 - cos) bump repeats every leg; the second leg runs the other way.
  const double direction = std::fmod(std::floor(time_ / leg_time_), 2.0) == 0.0 ? 1.0 : -1.0;
  const double omega =
      direction * omega_max_ / 2.0 * (1.0 - std::cos(2.0 * M_PI / leg_time_ * time_));
  std::array<double, 7> dq_command{};
  for (size_t joint = 0; joint < 7; ++joint) {
    dq_command[joint] = moving_joints_[joint] ? omega : 0.0;
  }

  franka::JointVelocities output(dq_command);
  if (time_ >= 2.0 * leg_time_) {
    std::cout << std::endl << "Finished motion." << std::endl;
    return franka::MotionFinished(output);
  }
  return output;
}

CartesianArc::CartesianArc(std::array<double, 16> franka::RobotState::*start_field)
    : start_field_(start_field) {}

franka::CartesianPose CartesianArc::operator()(const franka::RobotState& robot_state,
                                               franka::Duration period) {
  time_ += period.toSec();
  if (time_ == 0.0) {
    pose_initial_ = robot_state.*start_field_;
  }

  constexpr double kRadius = 0.3;  // [m]
  // The angle along the arc rises from 0 to pi/2 and returns, as 1 - cos over one 10 s period.
  const double angle = M_PI / 4.0 * (1.0 - std::cos(2.0 * M_PI / 10.0 * time_));
  std::array<double, 16> pose = pose_initial_;  // column-major: translation in 12, 13, 14
  pose[12] += kRadius * std::sin(angle);
  pose[14] += kRadius * (std::cos(angle) - 1.0);

  if (time_ >= 10.0) {
    std::cout << std::endl << "Finished motion, shutting down example" << std::endl;
    return franka::MotionFinished(franka::CartesianPose(pose));
  }
  return franka::CartesianPose(pose);
}

franka::CartesianVelocities CartesianVelocityWave::operator()(
    const franka::RobotState& /*robot_state*/,
    franka::Duration period) {
  time_ += period.toSec();

  constexpr double kLegTime = 4.0;       // [s]
  constexpr double kSpeedMax = 0.1;      // [m/s]
  constexpr double kAngle = M_PI / 4.0;  // below the horizontal
  const double direction = std::fmod(std::floor(time_ / kLegTime), 2.0) == 0.0 ? 1.0 : -1.0;
  const double speed =
      direction * kSpeedMax / 2.0 * (1.0 - std::cos(2.0 * M_PI / kLegTime * time_));

  const std::array<double, 6> twist{
      {std::cos(kAngle) * speed, 0.0, -std::sin(kAngle) * speed, 0.0, 0.0, 0.0}};
  franka::CartesianVelocities output(twist);
  if (time_ >= 2.0 * kLegTime) {
    std::cout << std::endl << "Finished motion, shutting down example" << std::endl;
    return franka::MotionFinished(output);
  }
  return output;
}

JointVelocityRamp::JointVelocityRamp(size_t joint, double a_max) : joint_(joint), a_max_(a_max) {}

franka::JointVelocities JointVelocityRamp::operator()(const franka::RobotState& /*robot_state*/,
                                                      franka::Duration period) {
  time_ += period.toSec();

  // Velocity reached after t of a_max sin^2(pi t): a_max (t / 2 - sin(2 pi t) / (4 pi)).
  auto ramp = [this](double t) {
    return a_max_ * (t / 2.0 - std::sin(2.0 * M_PI * t) / (4.0 * M_PI));
  };
  const double cruise = ramp(1.0);
  double velocity = 0.0;
  if (time_ <= 1.0) {
    velocity = ramp(time_);
  } else if (time_ <= 2.0) {
    velocity = cruise;
  } else if (time_ < 3.0) {
    velocity = cruise - ramp(time_ - 2.0);
  }

  std::array<double, 7> dq_command{};
  dq_command[joint_] = velocity;
  franka::JointVelocities output(dq_command);
  if (time_ >= 3.0) {
    return franka::MotionFinished(output);
  }
  return output;
}

JointPdController::JointPdController(const std::array<double, 7>& K_P,
                                     const std::array<double, 7>& K_D)
    : K_P_(K_P), K_D_(K_D) {}

franka::Torques JointPdController::operator()(const franka::RobotState& robot_state,
                                              franka::Duration /*period*/) {
  dq_history_[next_] = robot_state.dq;
  next_ = (next_ + 1) % kFilterSize;

  std::array<double, 7> tau_d{};
  for (size_t joint = 0; joint < 7; ++joint) {
    double dq_mean = 0.0;
    for (const auto& dq : dq_history_) {
      dq_mean += dq[joint] / kFilterSize;
    }
    tau_d[joint] =
        K_P_[joint] * (robot_state.q_d[joint] - robot_state.q[joint]) - K_D_[joint] * dq_mean;
  }
  return franka::Torques(tau_d);
}

void writeLogToFile(const std::vector<franka::Record>& log) {
  if (log.empty()) {
    return;
  }
  try {
    const std::filesystem::path folder = std::filesystem::temp_directory_path() / "libfranka-logs";
    std::filesystem::create_directories(folder);
    const auto now = std::chrono::duration_cast<std::chrono::milliseconds>(
        std::chrono::system_clock::now().time_since_epoch());
    const std::filesystem::path file = folder / ("log-" + std::to_string(now.count()) + ".csv");
    std::ofstream stream(file);
    stream << franka::logToCSV(log);
    if (!stream) {
      std::cout << "Failed to write log file." << std::endl;
      return;
    }
    std::cout << "Log file written to: " << file.string() << std::endl;
  } catch (const std::exception&) {
    std::cout << "Failed to write log file." << std::endl;
  }
}
