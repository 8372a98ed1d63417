// The robot's 1 kHz state and command as the FCI sends them, with libfranka's names
// (research_interface::robot): what programs written against libfranka include, e.g. franka_ros2's
// franka_hardware. CSP's franka::Robot does not send them (it has no network); they are here so that
// such programs build unchanged, and they have the robot's layout: packed, every field in the
// robot's order, as in the two FCI versions `csp fci` serves. CSP_FRANKA_API_VERSION chooses one:
// 1500 gives version 7's (libfranka 0.13: doubles throughout), 900 version 5's (libfranka 0.9:
// no MotionGeneratorMode::kNone, no torque_command_finished). Newer robots send the state's values
// as floats (docs/franka_api.md).
#pragma once

#include <array>
#include <cstdint>

#include "franka/api_version.h"

namespace research_interface {
namespace robot {

#pragma pack(push, 1)

// Modes as the state reports them (the Move request has its own codes: service_types.h).
enum class MotionGeneratorMode : uint8_t {
  kIdle,
  kJointPosition,
  kJointVelocity,
  kCartesianPosition,
  kCartesianVelocity,
#if CSP_FRANKA_API_VERSION >= 1000
  kNone,
#endif
};
enum class ControllerMode : uint8_t { kJointImpedance, kCartesianImpedance, kExternalController, kOther };
enum class RobotMode : uint8_t { kOther, kIdle, kMove, kGuiding, kReflex, kUserStopped, kAutomaticErrorRecovery };

// One state: franka::RobotState's values, poses and matrices column-major.
struct RobotState {
  uint64_t message_id;
  std::array<double, 16> O_T_EE, O_T_EE_d, F_T_EE, EE_T_K, F_T_NE, NE_T_EE;
  double m_ee;
  std::array<double, 9> I_ee;
  std::array<double, 3> F_x_Cee;
  double m_load;
  std::array<double, 9> I_load;
  std::array<double, 3> F_x_Cload;
  std::array<double, 2> elbow, elbow_d;
  std::array<double, 7> tau_J, tau_J_d, dtau_J, q, q_d, dq, dq_d, ddq_d, joint_contact;
  std::array<double, 6> cartesian_contact;
  std::array<double, 7> joint_collision;
  std::array<double, 6> cartesian_collision;
  std::array<double, 7> tau_ext_hat_filtered;
  std::array<double, 6> O_F_ext_hat_K, K_F_ext_hat_K, O_dP_EE_d;
  std::array<double, 3> O_ddP_O;
  std::array<double, 2> elbow_c, delbow_c, ddelbow_c;
  std::array<double, 16> O_T_EE_c;
  std::array<double, 6> O_dP_EE_c, O_ddP_EE_c;
  std::array<double, 7> theta, dtheta;
  MotionGeneratorMode motion_generator_mode;
  ControllerMode controller_mode;
  std::array<bool, 41> errors;          // in the research interface's Error order (not franka::Errors' fields')
  std::array<bool, 41> reflex_reason;   // the errors that ended the last motion
  RobotMode robot_mode;
  double control_command_success_rate;
};

// The command answering the state with the same message_id.
struct MotionGeneratorCommand {
  std::array<double, 7> q_c, dq_c;
  std::array<double, 16> O_T_EE_c;
  std::array<double, 6> O_dP_EE_c;
  std::array<double, 2> elbow_c;
  bool valid_elbow;
  bool motion_generation_finished;
};
struct ControllerCommand {
  std::array<double, 7> tau_J_d;
#if CSP_FRANKA_API_VERSION >= 1000
  bool torque_command_finished;
#endif
};
struct RobotCommand {
  uint64_t message_id;
  MotionGeneratorCommand motion;
  ControllerCommand control;
};

#pragma pack(pop)

}  // namespace robot
}  // namespace research_interface
