// The robot state with libfranka's field names, units and conventions: franka::RobotState itself
// (rt/franka/include/franka/robot_state.h), so that the emulator publishes what a libfranka
// program reads, without a copy.
#pragma once

#include "csp/rt/duration.hpp"
#include "csp/rt/errors.hpp"
#include "franka/robot_state.h"

namespace csp::rt {

using RobotState = franka::RobotState;
using RobotMode = franka::RobotMode;

const char* robot_mode_name(RobotMode mode);

// Every field of RobotState in declaration order, for the code that handles each of them: the
// JSON writer below, the LCM conversion (bridge/src/messages.cpp, bridge/lcm/robot_state_t.lcm).
// D(name): a field of doubles (one or an std::array); O(name): a field of another type, which
// each user handles by hand. tests/test_state_fields.cpp checks that the list holds every field
// of the struct and that robot_state_t.lcm declares each one.
#define CSP_ROBOT_STATE_FIELDS(D, O)                                                                   \
  D(O_T_EE) D(O_T_EE_d) D(F_T_EE) D(F_T_NE) D(NE_T_EE) D(EE_T_K) D(m_ee) D(I_ee) D(F_x_Cee) D(m_load)   \
  D(I_load) D(F_x_Cload) D(m_total) D(I_total) D(F_x_Ctotal) D(elbow) D(elbow_d) D(elbow_c) D(delbow_c) \
  D(ddelbow_c) D(tau_J) D(tau_J_d) D(dtau_J) D(q) D(q_d) D(dq) D(dq_d) D(ddq_d) D(joint_contact)        \
  D(cartesian_contact) D(joint_collision) D(cartesian_collision) D(tau_ext_hat_filtered) D(O_F_ext_hat_K) \
  D(K_F_ext_hat_K) D(O_dP_EE_d) D(O_ddP_O) D(O_T_EE_c) D(O_dP_EE_c) D(O_ddP_EE_c) D(theta) D(dtheta)   \
  O(current_errors) O(last_motion_errors) D(control_command_success_rate) O(robot_mode) O(time)


}  // namespace csp::rt
