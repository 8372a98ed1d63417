// franka::RobotState and franka::RobotMode: the robot's state, field for field libfranka 0.15's
// (same names, types, order, units and frames). Self-contained: a libfranka program includes it as
// it is, and CSP's emulator publishes this very struct (csp::rt::RobotState is an alias).
#pragma once

#include <array>
#include <ostream>

#include "franka/duration.h"
#include "franka/errors.h"

namespace franka {

// The robot's mode, as the robot reports it.
enum class RobotMode { kOther, kIdle, kMove, kGuiding, kReflex, kUserStopped, kAutomaticErrorRecovery };

// Frames: O base, F flange, NE nominal end effector, EE end effector, K stiffness frame. Poses
// are 4x4 homogeneous transforms a_T_b (frame b in frame a), column-major; 3x3 inertias
// column-major; twists and wrenches 6-vectors, linear (or force) first.
struct RobotState {
  std::array<double, 16> O_T_EE{};      // measured EE pose in the base frame, by the robot's model at q
  std::array<double, 16> O_T_EE_d{};    // last desired EE pose of motion generation, base frame
  std::array<double, 16> F_T_EE{};      // EE pose in the flange frame (F_T_NE NE_T_EE)
  std::array<double, 16> F_T_NE{};      // nominal EE pose in the flange frame (the configured end effector)
  std::array<double, 16> NE_T_EE{};     // EE pose in the nominal EE frame (Robot::setEE)
  std::array<double, 16> EE_T_K{};      // stiffness frame pose in the EE frame (Robot::setK)
  double m_ee{};                        // configured end-effector mass [kg]
  std::array<double, 9> I_ee{};         // configured end-effector inertia about its CoM, flange axes [kg m^2]
  std::array<double, 3> F_x_Cee{};      // configured end-effector CoM in the flange frame [m]
  double m_load{};                      // configured external load mass [kg] (Robot::setLoad)
  std::array<double, 9> I_load{};       // configured load inertia about its CoM, flange axes [kg m^2]
  std::array<double, 3> F_x_Cload{};    // configured load CoM in the flange frame [m]
  double m_total{};                     // end effector and load combined: m_ee + m_load [kg]
  std::array<double, 9> I_total{};      // combined inertia about the combined CoM, flange axes [kg m^2]
  std::array<double, 3> F_x_Ctotal{};   // combined CoM in the flange frame [m]
  std::array<double, 2> elbow{};        // measured elbow: joint 3 position [rad], sign of joint 4 (+1 or -1)
  std::array<double, 2> elbow_d{};      // desired elbow: joint 3 position [rad], sign of joint 4
  std::array<double, 2> elbow_c{};      // commanded elbow: joint 3 position [rad], sign of joint 4
  std::array<double, 2> delbow_c{};     // commanded elbow velocity: joint 3 [rad/s], sign of joint 4
  std::array<double, 2> ddelbow_c{};    // commanded elbow acceleration: joint 3 [rad/s^2], sign of joint 4
  std::array<double, 7> tau_J{};        // measured link-side joint torques, gravity included [N m]
  std::array<double, 7> tau_J_d{};      // desired link-side joint torques without gravity [N m]
  std::array<double, 7> dtau_J{};       // time derivative of tau_J [N m/s]
  std::array<double, 7> q{};            // measured joint positions [rad]
  std::array<double, 7> q_d{};          // desired joint positions [rad]
  std::array<double, 7> dq{};           // measured joint velocities [rad/s]
  std::array<double, 7> dq_d{};         // desired joint velocities [rad/s]
  std::array<double, 7> ddq_d{};        // desired joint accelerations [rad/s^2]
  std::array<double, 7> joint_contact{};        // per joint: 1 while |tau_ext| is over the contact threshold
  std::array<double, 6> cartesian_contact{};    // per K axis (x y z R P Y): 1 while over the contact threshold
  std::array<double, 7> joint_collision{};      // per joint: 1 from the collision threshold to error recovery
  std::array<double, 6> cartesian_collision{};  // per K axis: 1 from the collision threshold to error recovery
  std::array<double, 7> tau_ext_hat_filtered{}; // external joint torques, low-pass filtered: tau_J minus the model's [N m]
  std::array<double, 6> O_F_ext_hat_K{};        // estimated external wrench on K, base-frame axes [N x3, N m x3]
  std::array<double, 6> K_F_ext_hat_K{};        // estimated external wrench on K, K axes [N x3, N m x3]
  std::array<double, 6> O_dP_EE_d{};            // desired EE twist in the base frame [m/s x3, rad/s x3]
  std::array<double, 3> O_ddP_O{};              // base acceleration, base frame; at rest the gravity vector, {0, 0, -9.81} [m/s^2]
  std::array<double, 16> O_T_EE_c{};            // last commanded EE pose of motion generation, base frame
  std::array<double, 6> O_dP_EE_c{};            // last commanded EE twist in the base frame [m/s x3, rad/s x3]
  std::array<double, 6> O_ddP_EE_c{};           // last commanded EE acceleration, base frame [m/s^2 x3, rad/s^2 x3]
  std::array<double, 7> theta{};                // motor positions, scaled to the link side [rad]
  std::array<double, 7> dtheta{};               // motor velocities, scaled to the link side [rad/s]
  Errors current_errors{};                      // errors of the current cycle
  Errors last_motion_errors{};                  // errors that aborted the previous motion
  double control_command_success_rate{};        // share of the last 100 commands received [0, 1]; 0 outside motions
  RobotMode robot_mode = RobotMode::kUserStopped;  // the robot's mode
  Duration time{};                              // time since the robot started, monotonic, 1 ms steps
};

// Streams the state as one JSON object, as libfranka does.
std::ostream& operator<<(std::ostream& ostream, const franka::RobotState& robot_state);
// Streams the mode's name, e.g. "Idle".
std::ostream& operator<<(std::ostream& ostream, RobotMode robot_mode);

}  // namespace franka
