// The robot state with libfranka's field names, units and conventions (franka::RobotState):
// poses 4x4 column-major, wrenches (force, torque), one doc line per field.
#pragma once

#include <array>
#include <ostream>

#include "csp/rt/duration.hpp"
#include "csp/rt/errors.hpp"

namespace csp::rt {

enum class RobotMode { kOther, kIdle, kMove, kGuiding, kReflex, kUserStopped, kAutomaticErrorRecovery };

const char* robot_mode_name(RobotMode mode);

struct RobotState {
  std::array<double, 16> O_T_EE{};      // measured EE pose in the base frame (robot's model), column-major
  std::array<double, 16> O_T_EE_d{};    // last desired EE pose of motion generation
  std::array<double, 16> F_T_EE{};      // EE frame in the flange frame (setEE)
  std::array<double, 16> F_T_NE{};      // nominal EE frame in the flange frame (the configured end effector)
  std::array<double, 16> NE_T_EE{};     // EE frame in the nominal EE frame
  std::array<double, 16> EE_T_K{};      // stiffness frame in the EE frame (setK)
  double m_ee{};                        // configured end-effector mass [kg]
  std::array<double, 9> I_ee{};         // end-effector inertia about its CoM [kg m^2], column-major
  std::array<double, 3> F_x_Cee{};      // end-effector CoM in the flange frame [m]
  double m_load{};                      // configured load mass [kg] (setLoad)
  std::array<double, 9> I_load{};       // load inertia about its CoM [kg m^2]
  std::array<double, 3> F_x_Cload{};    // load CoM in the flange frame [m]
  double m_total{};                     // m_ee + m_load [kg]
  std::array<double, 9> I_total{};      // combined inertia about the combined CoM [kg m^2]
  std::array<double, 3> F_x_Ctotal{};   // combined CoM in the flange frame [m]
  std::array<double, 2> elbow{};        // (q3 [rad], sign of q4)
  std::array<double, 2> elbow_d{};      // desired elbow
  std::array<double, 2> elbow_c{};      // commanded elbow
  std::array<double, 2> delbow_c{};     // commanded elbow velocity
  std::array<double, 2> ddelbow_c{};    // commanded elbow acceleration
  std::array<double, 7> tau_J{};        // measured link-side joint torques, gravity included [N m]
  std::array<double, 7> tau_J_d{};      // desired link-side joint torques without gravity [N m]
  std::array<double, 7> dtau_J{};       // derivative of tau_J [N m/s]
  std::array<double, 7> q{};            // measured joint position [rad]
  std::array<double, 7> q_d{};          // desired joint position [rad]
  std::array<double, 7> dq{};           // measured joint velocity [rad/s]
  std::array<double, 7> dq_d{};         // desired joint velocity [rad/s]
  std::array<double, 7> ddq_d{};        // desired joint acceleration [rad/s^2]
  std::array<double, 7> joint_contact{};        // 1 where |tau_ext| exceeds the lower (contact) threshold
  std::array<double, 6> cartesian_contact{};    // 1 where |K_F_ext| exceeds the lower threshold
  std::array<double, 7> joint_collision{};      // 1 where the upper (collision) threshold was exceeded; latched
  std::array<double, 6> cartesian_collision{};  // latched like joint_collision
  std::array<double, 7> tau_ext_hat_filtered{}; // low-pass of tau_J minus the model's expected torque [N m]
  std::array<double, 6> O_F_ext_hat_K{};        // estimated external wrench on K, base frame [N, N m]
  std::array<double, 6> K_F_ext_hat_K{};        // the same wrench in the K frame [N, N m]
  std::array<double, 6> O_dP_EE_d{};            // desired EE twist in the base frame [m/s, rad/s]
  std::array<double, 3> O_ddP_O{};              // gravity-free base acceleration [m/s^2] (fixed base: -gravity)
  std::array<double, 16> O_T_EE_c{};            // last commanded EE pose
  std::array<double, 6> O_dP_EE_c{};            // last commanded EE twist
  std::array<double, 6> O_ddP_EE_c{};           // last commanded EE acceleration
  std::array<double, 7> theta{};                // motor position [rad] (link side, as libfranka reports)
  std::array<double, 7> dtheta{};               // motor velocity [rad/s]
  Errors current_errors{};                      // errors of the current state
  Errors last_motion_errors{};                  // errors that aborted the previous motion
  double control_command_success_rate{};        // share of the last 100 commands received, 0 when no motion runs
  RobotMode robot_mode = RobotMode::kIdle;
  Duration time{};                              // time since the robot started, 1 ms steps
};

// Streams the state as one JSON object, as libfranka does.
std::ostream& operator<<(std::ostream& out, const RobotState& state);

}  // namespace csp::rt
