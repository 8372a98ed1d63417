// CSP's <research_interface/robot/rbk_types.h> (rt/franka/include) against the vendored libfranka's
// own header, the independent reference: the same names, sizes, offsets and enumerator values.
// Built twice (tests/CMakeLists.txt): CSP_FRANKA_API_VERSION 1500 against libfranka 0.13.3's
// header, 900 against 0.9.2's (CSP_VENDOR_RBK_TYPES_H names the file, CSP_RBK_SUITE the suite).
#include <cstddef>

#include <gtest/gtest.h>

#include <research_interface/robot/rbk_types.h>

// libfranka's header in a namespace of its own: it declares the same names.
namespace vendor {
#include CSP_VENDOR_RBK_TYPES_H
}  // namespace vendor

namespace {

namespace csp_ri = research_interface::robot;
namespace ri = vendor::research_interface::robot;

#define CSP_EXPECT_FIELD(type, field)                                               \
  EXPECT_EQ(offsetof(csp_ri::type, field), offsetof(ri::type, field)) << #field;   \
  EXPECT_EQ(sizeof(csp_ri::type::field), sizeof(ri::type::field)) << #field

#define CSP_EXPECT_ENUMERATOR(type, name) \
  EXPECT_EQ(static_cast<int>(csp_ri::type::name), static_cast<int>(ri::type::name)) << #type "::" #name

TEST(CSP_RBK_SUITE, RobotStateHasTheRobotsLayout) {
  EXPECT_EQ(sizeof(csp_ri::RobotState), sizeof(ri::RobotState));
  CSP_EXPECT_FIELD(RobotState, message_id);
  CSP_EXPECT_FIELD(RobotState, O_T_EE);
  CSP_EXPECT_FIELD(RobotState, O_T_EE_d);
  CSP_EXPECT_FIELD(RobotState, F_T_EE);
  CSP_EXPECT_FIELD(RobotState, EE_T_K);
  CSP_EXPECT_FIELD(RobotState, F_T_NE);
  CSP_EXPECT_FIELD(RobotState, NE_T_EE);
  CSP_EXPECT_FIELD(RobotState, m_ee);
  CSP_EXPECT_FIELD(RobotState, I_ee);
  CSP_EXPECT_FIELD(RobotState, F_x_Cee);
  CSP_EXPECT_FIELD(RobotState, m_load);
  CSP_EXPECT_FIELD(RobotState, I_load);
  CSP_EXPECT_FIELD(RobotState, F_x_Cload);
  CSP_EXPECT_FIELD(RobotState, elbow);
  CSP_EXPECT_FIELD(RobotState, elbow_d);
  CSP_EXPECT_FIELD(RobotState, tau_J);
  CSP_EXPECT_FIELD(RobotState, tau_J_d);
  CSP_EXPECT_FIELD(RobotState, dtau_J);
  CSP_EXPECT_FIELD(RobotState, q);
  CSP_EXPECT_FIELD(RobotState, q_d);
  CSP_EXPECT_FIELD(RobotState, dq);
  CSP_EXPECT_FIELD(RobotState, dq_d);
  CSP_EXPECT_FIELD(RobotState, ddq_d);
  CSP_EXPECT_FIELD(RobotState, joint_contact);
  CSP_EXPECT_FIELD(RobotState, cartesian_contact);
  CSP_EXPECT_FIELD(RobotState, joint_collision);
  CSP_EXPECT_FIELD(RobotState, cartesian_collision);
  CSP_EXPECT_FIELD(RobotState, tau_ext_hat_filtered);
  CSP_EXPECT_FIELD(RobotState, O_F_ext_hat_K);
  CSP_EXPECT_FIELD(RobotState, K_F_ext_hat_K);
  CSP_EXPECT_FIELD(RobotState, O_dP_EE_d);
  CSP_EXPECT_FIELD(RobotState, O_ddP_O);
  CSP_EXPECT_FIELD(RobotState, elbow_c);
  CSP_EXPECT_FIELD(RobotState, delbow_c);
  CSP_EXPECT_FIELD(RobotState, ddelbow_c);
  CSP_EXPECT_FIELD(RobotState, O_T_EE_c);
  CSP_EXPECT_FIELD(RobotState, O_dP_EE_c);
  CSP_EXPECT_FIELD(RobotState, O_ddP_EE_c);
  CSP_EXPECT_FIELD(RobotState, theta);
  CSP_EXPECT_FIELD(RobotState, dtheta);
  CSP_EXPECT_FIELD(RobotState, motion_generator_mode);
  CSP_EXPECT_FIELD(RobotState, controller_mode);
  CSP_EXPECT_FIELD(RobotState, errors);
  CSP_EXPECT_FIELD(RobotState, reflex_reason);
  CSP_EXPECT_FIELD(RobotState, robot_mode);
  CSP_EXPECT_FIELD(RobotState, control_command_success_rate);
}

TEST(CSP_RBK_SUITE, RobotCommandHasTheRobotsLayout) {
  EXPECT_EQ(sizeof(csp_ri::MotionGeneratorCommand), sizeof(ri::MotionGeneratorCommand));
  CSP_EXPECT_FIELD(MotionGeneratorCommand, q_c);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, dq_c);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, O_T_EE_c);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, O_dP_EE_c);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, elbow_c);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, valid_elbow);
  CSP_EXPECT_FIELD(MotionGeneratorCommand, motion_generation_finished);
  EXPECT_EQ(sizeof(csp_ri::ControllerCommand), sizeof(ri::ControllerCommand));
  CSP_EXPECT_FIELD(ControllerCommand, tau_J_d);
#if CSP_FRANKA_API_VERSION >= 1000
  CSP_EXPECT_FIELD(ControllerCommand, torque_command_finished);
#endif
  EXPECT_EQ(sizeof(csp_ri::RobotCommand), sizeof(ri::RobotCommand));
  CSP_EXPECT_FIELD(RobotCommand, message_id);
  CSP_EXPECT_FIELD(RobotCommand, motion);
  CSP_EXPECT_FIELD(RobotCommand, control);
}

TEST(CSP_RBK_SUITE, ModesHaveTheRobotsCodes) {
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kIdle);
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kJointPosition);
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kJointVelocity);
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kCartesianPosition);
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kCartesianVelocity);
#if CSP_FRANKA_API_VERSION >= 1000
  CSP_EXPECT_ENUMERATOR(MotionGeneratorMode, kNone);
#endif
  CSP_EXPECT_ENUMERATOR(ControllerMode, kJointImpedance);
  CSP_EXPECT_ENUMERATOR(ControllerMode, kCartesianImpedance);
  CSP_EXPECT_ENUMERATOR(ControllerMode, kExternalController);
  CSP_EXPECT_ENUMERATOR(ControllerMode, kOther);
  CSP_EXPECT_ENUMERATOR(RobotMode, kOther);
  CSP_EXPECT_ENUMERATOR(RobotMode, kIdle);
  CSP_EXPECT_ENUMERATOR(RobotMode, kMove);
  CSP_EXPECT_ENUMERATOR(RobotMode, kGuiding);
  CSP_EXPECT_ENUMERATOR(RobotMode, kReflex);
  CSP_EXPECT_ENUMERATOR(RobotMode, kUserStopped);
  CSP_EXPECT_ENUMERATOR(RobotMode, kAutomaticErrorRecovery);
}

}  // namespace
