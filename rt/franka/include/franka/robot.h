// franka::Robot: the emulated robot behind libfranka's Robot interface. A controller written for
// libfranka builds against CSP by linking Franka::Franka; the constructor takes a scenario
// (configs/scenarios/*.yaml) instead of the robot's IP address.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"
#include "franka/control_types.h"
#include "franka/duration.h"
#include "franka/exception.h"
#include "franka/log.h"
#include "franka/lowpass_filter.h"
#include "franka/model.h"
#include "franka/robot_state.h"

namespace franka {

class Robot {
 public:
  // Cycles kept in ControlException::log (libfranka's default log_size).
  static constexpr std::size_t kLogSize = 50;

  // The robot of a scenario file, or of a scenario built in code. realtime_config matters on the
  // scenario's real-time clock only; the lockstep clock needs no real-time scheduling.
  explicit Robot(const std::string& scenario_path, RealtimeConfig realtime_config = RealtimeConfig::kEnforce);
  explicit Robot(const csp::rt::Scenario& scenario, RealtimeConfig realtime_config = RealtimeConfig::kEnforce);

  // Runs one motion, calling the callback once per 1 ms cycle (period 0 at the first call) until
  // it returns a command marked MotionFinished. Commands are low-pass filtered below
  // kMaxCutoffFrequency and, with limit_rate, rate limited as libfranka does.
  // Throws ControlException when the motion ends in a reflex (what() names the errors) or cannot
  // start (robot in Reflex: call automaticErrorRecovery first), CommandException for a NaN or
  // infinite command (the robot then is in Reflex), InvalidOperationException for
  // ControllerMode::kCartesianImpedance, RealtimeException without real-time scheduling under
  // kEnforce. An exception thrown by the callback ends the motion in Reflex and is rethrown.
  void control(std::function<Torques(const RobotState&, franka::Duration)> control_callback,
               bool limit_rate = false, double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<JointPositions(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance, bool limit_rate = false,
               double cutoff_frequency = kDefaultCutoffFrequency);
  void control(std::function<JointVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
               ControllerMode controller_mode = ControllerMode::kJointImpedance, bool limit_rate = false,
               double cutoff_frequency = kDefaultCutoffFrequency);

  // Reads states until the callback returns false; readOnce reads one. Each read waits for the
  // robot's next 1 ms cycle (see readOnce in robot.cpp).
  void read(std::function<bool(const RobotState&)> read_callback);
  RobotState readOnce();

  // Contact (lower) and collision (upper) thresholds: the same for acceleration and nominal
  // phases, or each given [N m for joints; N, N m for the Cartesian wrench].
  void setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds,
                            const std::array<double, 7>& upper_torque_thresholds,
                            const std::array<double, 6>& lower_force_thresholds,
                            const std::array<double, 6>& upper_force_thresholds);
  void setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds_acceleration,
                            const std::array<double, 7>& upper_torque_thresholds_acceleration,
                            const std::array<double, 7>& lower_torque_thresholds_nominal,
                            const std::array<double, 7>& upper_torque_thresholds_nominal,
                            const std::array<double, 6>& lower_force_thresholds_acceleration,
                            const std::array<double, 6>& upper_force_thresholds_acceleration,
                            const std::array<double, 6>& lower_force_thresholds_nominal,
                            const std::array<double, 6>& upper_force_thresholds_nominal);
  // Stiffness of the robot's joint impedance controller [N m/rad].
  void setJointImpedance(const std::array<double, 7>& K_theta);   // NOLINT(readability-identifier-naming)
  // The load the robot is told it carries: mass [kg], CoM in the flange frame [m], inertia about
  // the CoM [kg m^2] column-major. Changes the robot's model only, not the emulated arm.
  void setLoad(double load_mass, const std::array<double, 3>& F_x_Cload,   // NOLINT(readability-identifier-naming)
               const std::array<double, 9>& load_inertia);
  void setEE(const std::array<double, 16>& NE_T_EE);   // NOLINT(readability-identifier-naming)
  void setK(const std::array<double, 16>& EE_T_K);     // NOLINT(readability-identifier-naming)
  // Clears the errors of a reflex and releases the brakes (Reflex -> Idle).
  void automaticErrorRecovery();
  // The robot's model as it is now configured (end effector, load, K frame).
  Model loadModel();

  // CSP extras (not in libfranka) ----------------------------------------------------------
  // The emulated robot itself, e.g. to read its counters or settings.
  csp::rt::Emulator& emulator() { return emulator_; }
  // Timing of the last control() call: cycles, lost commands, overruns, controller compute time.
  const csp::rt::TimingReport& lastTiming() const { return last_timing_; }
  // Called after every cycle of control() with the published state, e.g. a csp::rt::CsvLog.
  void setCycleObserver(csp::rt::CycleObserver observer) { user_observer_ = std::move(observer); }

 private:
  template <typename Command>
  void run(csp::rt::ControlMode mode, const std::function<Command(const RobotState&, franka::Duration)>& callback,
           ControllerMode controller_mode, bool limit_rate, double cutoff_frequency);
  // libfranka's client-side processing of a finite command: low-pass filter, then rate limit.
  std::array<double, 7> shape(csp::rt::ControlMode mode, std::array<double, 7> values, const RobotState& state,
                              bool limit_rate, double cutoff_frequency) const;
  void record(const RobotState& state, const csp::rt::CycleInfo& cycle);
  std::vector<Record> recent_log() const;

  csp::rt::Emulator emulator_;
  csp::rt::LoopOptions loop_options_;
  csp::rt::TimingReport last_timing_;
  csp::rt::CycleObserver user_observer_;
  std::array<Record, kLogSize> log_{};   // ring buffer of the last cycles
  std::size_t log_next_ = 0, log_count_ = 0;
};

}  // namespace franka
