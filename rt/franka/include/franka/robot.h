// franka::Robot: the emulated robot behind libfranka's Robot interface (libfranka 0.15's class:
// the same constructors, methods, defaults and exceptions). A libfranka program builds against
// CSP unchanged by linking Franka::Franka. The robot's address names the robot to emulate
// (docs/franka_api.md, "The robot's address"): a scenario file, or an IP address / hostname, for
// which $CSP_SCENARIO or configs/scenarios/libfranka_panda.yaml chooses the scenario.
// The emulator lives behind Impl, so this class's layout does not depend on the flags a program
// is compiled with. Self-contained, C++14.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "franka/api_version.h"
#include "franka/control_types.h"
#include "franka/duration.h"
#include "franka/lowpass_filter.h"
#include "franka/robot_state.h"
#include "research_interface/robot/service_types.h"

namespace franka {

class Model;
class ActiveControlBase;

class Robot {
 public:
  // The robot server's version (CSP reports libfranka 0.15's robot server, 9).
  using ServerVersion = uint16_t;

  // Connects to the robot at `franka_address` (in CSP: loads the robot its address names).
  // log_size: cycles kept in ControlException::log. Throws NetworkException if the address names
  // no robot (no scenario that loads), std::invalid_argument for log_size 0.
  explicit Robot(const std::string& franka_address, RealtimeConfig realtime_config = RealtimeConfig::kEnforce,
                 size_t log_size = 50);
  Robot(Robot&& other) noexcept;
  Robot& operator=(Robot&& other) noexcept;
  virtual ~Robot() noexcept;

  // Motions: the callback is called once per received state, with the robot time since its
  // previous call (0 at the first), until it returns a command marked MotionFinished. Commands are
  // low-pass filtered below kMaxCutoffFrequency and, with limit_rate, rate limited as libfranka
  // does. Throws ControlException when the motion ends in a reflex (what() names the errors), is
  // preempted by stop(), or cannot start (robot in Reflex); InvalidOperationException while
  // another motion runs; RealtimeException without real-time scheduling under kEnforce (on the
  // real-time clock only); std::invalid_argument for a NaN or infinite command (the robot then
  // stops in a reflex). An exception thrown by a callback ends the motion and is rethrown.
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               std::function<JointPositions(const RobotState&, franka::Duration)> motion_generator_callback,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               std::function<JointVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               std::function<CartesianPose(const RobotState&, franka::Duration)> motion_generator_callback,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               std::function<CartesianVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<JointPositions(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<JointVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<CartesianPose(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<CartesianVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance,
               bool limit_rate = detail::kDefaultLimitRate, double cutoff_frequency = kDefaultCutoffFrequency);

  // Reads states until the callback returns false; readOnce reads one. Each read returns the
  // robot's next 1 ms cycle. InvalidOperationException while a motion runs.
  void read(std::function<bool(const RobotState&)> read_callback);
  virtual RobotState readOnce();

  // Contact (lower) and collision (upper) thresholds: separate for acceleration and nominal
  // phases, or common [N m for joints; N, N m for the Cartesian wrench].
  void setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds_acceleration,
                            const std::array<double, 7>& upper_torque_thresholds_acceleration,
                            const std::array<double, 7>& lower_torque_thresholds_nominal,
                            const std::array<double, 7>& upper_torque_thresholds_nominal,
                            const std::array<double, 6>& lower_force_thresholds_acceleration,
                            const std::array<double, 6>& upper_force_thresholds_acceleration,
                            const std::array<double, 6>& lower_force_thresholds_nominal,
                            const std::array<double, 6>& upper_force_thresholds_nominal);
  void setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds,
                            const std::array<double, 7>& upper_torque_thresholds,
                            const std::array<double, 6>& lower_force_thresholds,
                            const std::array<double, 6>& upper_force_thresholds);
  // Stiffness of the robot's joint impedance controller [N m/rad].
  void setJointImpedance(const std::array<double, 7>& K_theta);   // NOLINT(readability-identifier-naming)
  // Stiffness of the robot's Cartesian impedance controller on K (x y z [N/m], R P Y [N m/rad]).
  void setCartesianImpedance(const std::array<double, 6>& K_x);   // NOLINT(readability-identifier-naming)
  // Which Cartesian directions (x y z R P Y) and whether the elbow are free in guiding mode (hand
  // guiding by the buttons at the flange: not emulated; the setting is checked and kept).
  void setGuidingMode(const std::array<bool, 6>& guiding_mode, bool elbow);
  void setK(const std::array<double, 16>& EE_T_K);     // NOLINT(readability-identifier-naming)
  void setEE(const std::array<double, 16>& NE_T_EE);   // NOLINT(readability-identifier-naming)
  // The load the robot is told it carries: mass [kg], CoM in the flange frame [m], inertia about
  // the CoM [kg m^2] column-major. Changes the robot's model only, not the emulated arm.
  void setLoad(double load_mass, const std::array<double, 3>& F_x_Cload,   // NOLINT(readability-identifier-naming)
               const std::array<double, 9>& load_inertia);
  // Clears the errors of a reflex and releases the brakes (Reflex -> Idle).
  void automaticErrorRecovery();

  // The external control loop: starts a motion and returns its handle; the program then calls
  // readOnce() and writeOnce() once per cycle (franka/active_control.h).
  virtual std::unique_ptr<ActiveControlBase> startTorqueControl();
  virtual std::unique_ptr<ActiveControlBase> startJointPositionControl(
      const research_interface::robot::Move::ControllerMode& control_type);
  virtual std::unique_ptr<ActiveControlBase> startJointVelocityControl(
      const research_interface::robot::Move::ControllerMode& control_type);
  virtual std::unique_ptr<ActiveControlBase> startCartesianPoseControl(
      const research_interface::robot::Move::ControllerMode& control_type);
  virtual std::unique_ptr<ActiveControlBase> startCartesianVelocityControl(
      const research_interface::robot::Move::ControllerMode& control_type);

  // Stops the running motion: a control() in another thread ends with ControlException
  // ("Move command preempted"), an external control loop's next readOnce throws it.
  void stop();

  // The robot's model as it is now configured (end effector, load, K frame).
  Model loadModel();

  // The arm's URDF (libfranka 0.15): the emulated arm's kinematics, link inertials and joint limits,
  // links and joints named <robot>_link0..8, <robot>_joint1..8 (robot: panda or fr3).
  std::string getRobotModel();

  ServerVersion serverVersion() const noexcept;

  Robot(const Robot&) = delete;
  Robot& operator=(const Robot&) = delete;

  class Impl;

 protected:
  explicit Robot(std::shared_ptr<Impl> robot_impl);
  Robot() = default;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace franka
