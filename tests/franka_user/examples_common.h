// What the example programs share: the robot's default behaviour, a joint-space motion to a goal,
// the way every moving example first goes to its start pose, and the motions that an example and
// its external-control-loop twin both run. Written against libfranka's public API only.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include <franka/control_types.h>
#include <franka/duration.h>
#include <franka/exception.h>
#include <franka/robot.h>
#include <franka/robot_state.h>

// Collision thresholds, joint impedance and Cartesian impedance suited to the examples.
void setDefaultBehavior(franka::Robot& robot);

// The collision thresholds most motion examples set after reaching their start pose
// [Nm] per joint and [N, Nm] per Cartesian axis, the same during acceleration and at speed.
void setMotionCollisionBehavior(franka::Robot& robot);

// Joint impedance and separate contact (lower) and collision (upper) thresholds for the Cartesian
// velocity examples, which move faster through space than the others.
void setCartesianVelocityBehavior(franka::Robot& robot);

// Warns that the robot will move, waits for Enter on stdin and moves to kStartPose.
void moveToStartPose(franka::Robot& robot);

// Joint configuration the moving examples start from [rad].
extern const std::array<double, 7> kStartPose;

// Moves all joints from where they are to q_goal on one synchronised quintic time law
// s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5: velocity and acceleration are zero at both ends, so the
// command is jerk-limited at start and goal. The duration is the shortest that keeps every joint
// within speed_factor times its velocity and acceleration bounds. Use as a Robot::control callback.
class MotionGenerator {
 public:
  // speed_factor in (0, 1]; throws std::invalid_argument otherwise.
  MotionGenerator(double speed_factor, const std::array<double, 7> q_goal);

  franka::JointPositions operator()(const franka::RobotState& robot_state, franka::Duration period);

 private:
  using Vector7d = Eigen::Matrix<double, 7, 1>;

  // Sets q_start_ and the motion's duration from the joint with the largest need for time.
  void plan(const Vector7d& q_start);

  Vector7d q_goal_;
  Vector7d q_start_ = Vector7d::Zero();
  Vector7d dq_max_;
  Vector7d ddq_max_;
  double duration_ = 0.0;  // [s]
  double time_ = 0.0;      // [s]
};

// Joints 4, 5 and 7 swing by pi/8 (1 - cos(2 pi t / 5)) from where the motion starts, for 5 s.
// start_field names the RobotState field the motion starts from (q or q_d).
class JointPositionWave {
 public:
  explicit JointPositionWave(std::array<double, 7> franka::RobotState::*start_field);
  franka::JointPositions operator()(const franka::RobotState& robot_state, franka::Duration period);

 private:
  std::array<double, 7> franka::RobotState::*start_field_;
  std::array<double, 7> q_initial_{};
  double time_ = 0.0;
};

// Joints 4 to 7 (or one joint) turn one way and back, each leg a (1 - cos) velocity bump of
// omega_max, leg_time long.
class JointVelocityWave {
 public:
  JointVelocityWave(double omega_max, double leg_time, std::array<bool, 7> moving_joints);
  franka::JointVelocities operator()(const franka::RobotState& robot_state,
                                     franka::Duration period);

 private:
  double omega_max_;
  double leg_time_;
  std::array<bool, 7> moving_joints_;
  double time_ = 0.0;
};

// The end effector travels a quarter circle of radius 0.3 m in the base's x-z plane and back,
// keeping its orientation, in 10 s. start_field names the RobotState field the motion starts from
// (O_T_EE or O_T_EE_c).
class CartesianArc {
 public:
  explicit CartesianArc(std::array<double, 16> franka::RobotState::*start_field);
  franka::CartesianPose operator()(const franka::RobotState& robot_state, franka::Duration period);

 private:
  std::array<double, 16> franka::RobotState::*start_field_;
  std::array<double, 16> pose_initial_{};
  double time_ = 0.0;
};

// The end effector moves down and forward at 45 degrees and back, each leg a (1 - cos) speed bump
// of 0.1 m/s lasting 4 s.
class CartesianVelocityWave {
 public:
  franka::CartesianVelocities operator()(const franka::RobotState& robot_state,
                                         franka::Duration period);

 private:
  double time_ = 0.0;
};

// Joint velocity profile of the motion_with_control examples: one joint accelerates with a
// sin^2-shaped acceleration of peak a_max for 1 s, cruises for 1 s and decelerates likewise.
class JointVelocityRamp {
 public:
  JointVelocityRamp(size_t joint, double a_max);
  franka::JointVelocities operator()(const franka::RobotState& robot_state,
                                     franka::Duration period);

 private:
  size_t joint_;
  double a_max_;  // [rad/s^2]
  double time_ = 0.0;
};

// Joint-space PD torque controller tracking the robot's q_d at zero velocity, with the measured
// velocity averaged over the last few cycles to quiet its noise.
class JointPdController {
 public:
  static constexpr size_t kFilterSize = 5;

  JointPdController(const std::array<double, 7>& K_P,   // NOLINT(readability-identifier-naming)
                    const std::array<double, 7>& K_D);  // NOLINT(readability-identifier-naming)
  franka::Torques operator()(const franka::RobotState& robot_state, franka::Duration period);

 private:
  std::array<double, 7> K_P_;  // NOLINT(readability-identifier-naming)
  std::array<double, 7> K_D_;  // NOLINT(readability-identifier-naming)
  std::array<std::array<double, 7>, kFilterSize> dq_history_{};
  size_t next_ = 0;  // the history entry the next measurement replaces
};

// Writes the log a ControlException carries (the last robot states and commands before the error)
// as CSV to <temp>/libfranka-logs/log-<time>.csv and says where.
void writeLogToFile(const std::vector<franka::Record>& log);
