// The checks of tests/test_fci_protocol_v5.cpp and _v7.cpp: CSP's FCI wire structs and codes
// (bridge/fci/protocol.hpp) against the vendored libfranka's own research-interface headers, the
// independent reference, field by field. The including file puts one version's headers in
// a namespace of its own, CSP_FCI_VENDOR, and defines CSP_FCI_VERSION and CSP_FCI_SUITE.
#include <cstddef>
#include <cstring>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "csp/fci/protocol.hpp"

namespace {

namespace ri = CSP_FCI_VENDOR::research_interface::robot;
namespace fci = csp::fci;
constexpr fci::Version kVersion = CSP_FCI_VERSION;

// Same offset and size: the field lies where libfranka reads it.
#define CSP_EXPECT_FIELD(csp_type, vendor_type, field)                                     \
  EXPECT_EQ(offsetof(csp_type, field), offsetof(vendor_type, field)) << #field;           \
  EXPECT_EQ(sizeof(csp_type::field), sizeof(vendor_type::field)) << #field

TEST(CSP_FCI_SUITE, TheVersionIsLibfrankas) { EXPECT_EQ(kVersion, ri::kVersion); }

TEST(CSP_FCI_SUITE, MessagesHaveLibfrankasSizesAndOffsets) {
  EXPECT_EQ(sizeof(fci::MessageHeader), sizeof(ri::CommandHeader));
  CSP_EXPECT_FIELD(fci::MessageHeader, ri::CommandHeader, command);
  CSP_EXPECT_FIELD(fci::MessageHeader, ri::CommandHeader, command_id);
  CSP_EXPECT_FIELD(fci::MessageHeader, ri::CommandHeader, size);
  EXPECT_EQ(sizeof(fci::ConnectRequest), sizeof(ri::Connect::Request));
  CSP_EXPECT_FIELD(fci::ConnectRequest, ri::Connect::Request, version);
  CSP_EXPECT_FIELD(fci::ConnectRequest, ri::Connect::Request, udp_port);
  // (The responses' status lies in a base class: no offsetof there; their bytes are compared.)
  EXPECT_EQ(sizeof(fci::ConnectResponse), sizeof(ri::Connect::Response));
  const ri::Connect::Response connected(ri::Connect::Status::kIncompatibleLibraryVersion);
  fci::ConnectResponse read;
  std::memcpy(static_cast<void*>(&read), &connected, sizeof(read));
  EXPECT_EQ(read.status, static_cast<uint8_t>(ri::Connect::Status::kIncompatibleLibraryVersion));
  EXPECT_EQ(+read.version, ri::kVersion);
  EXPECT_EQ(sizeof(fci::MoveRequest), sizeof(ri::Move::Request));
  CSP_EXPECT_FIELD(fci::MoveRequest, ri::Move::Request, controller_mode);
  CSP_EXPECT_FIELD(fci::MoveRequest, ri::Move::Request, motion_generator_mode);
  CSP_EXPECT_FIELD(fci::MoveRequest, ri::Move::Request, maximum_path_deviation);
  CSP_EXPECT_FIELD(fci::MoveRequest, ri::Move::Request, maximum_goal_pose_deviation);
  EXPECT_EQ(sizeof(fci::CollisionBehaviorRequest), sizeof(ri::SetCollisionBehavior::Request));
  CSP_EXPECT_FIELD(fci::CollisionBehaviorRequest, ri::SetCollisionBehavior::Request, lower_torque_thresholds_acceleration);
  CSP_EXPECT_FIELD(fci::CollisionBehaviorRequest, ri::SetCollisionBehavior::Request, upper_torque_thresholds_nominal);
  CSP_EXPECT_FIELD(fci::CollisionBehaviorRequest, ri::SetCollisionBehavior::Request, lower_force_thresholds_acceleration);
  CSP_EXPECT_FIELD(fci::CollisionBehaviorRequest, ri::SetCollisionBehavior::Request, upper_force_thresholds_nominal);
  EXPECT_EQ(sizeof(fci::JointImpedanceRequest), sizeof(ri::SetJointImpedance::Request));
  EXPECT_EQ(sizeof(fci::CartesianImpedanceRequest), sizeof(ri::SetCartesianImpedance::Request));
  EXPECT_EQ(sizeof(fci::GuidingModeRequest), sizeof(ri::SetGuidingMode::Request));
  CSP_EXPECT_FIELD(fci::GuidingModeRequest, ri::SetGuidingMode::Request, nullspace);
  EXPECT_EQ(sizeof(fci::EEToKRequest), sizeof(ri::SetEEToK::Request));
  EXPECT_EQ(sizeof(fci::NEToEERequest), sizeof(ri::SetNEToEE::Request));
  EXPECT_EQ(sizeof(fci::LoadRequest), sizeof(ri::SetLoad::Request));
  CSP_EXPECT_FIELD(fci::LoadRequest, ri::SetLoad::Request, m_load);
  CSP_EXPECT_FIELD(fci::LoadRequest, ri::SetLoad::Request, F_x_Cload);
  CSP_EXPECT_FIELD(fci::LoadRequest, ri::SetLoad::Request, I_load);
  EXPECT_EQ(sizeof(fci::LoadModelLibraryRequest), sizeof(ri::LoadModelLibrary::Request));
  CSP_EXPECT_FIELD(fci::LoadModelLibraryRequest, ri::LoadModelLibrary::Request, system);
  EXPECT_EQ(sizeof(fci::StatusResponse), sizeof(ri::Move::Response));
#if CSP_FCI_VERSION == 5
  EXPECT_EQ(sizeof(fci::FiltersRequest), sizeof(ri::SetFilters::Request));
  CSP_EXPECT_FIELD(fci::FiltersRequest, ri::SetFilters::Request, controller_filter_frequency);
  EXPECT_EQ(sizeof(fci::GetCartesianLimitRequest), sizeof(ri::GetCartesianLimit::Request));
  EXPECT_EQ(sizeof(fci::GetCartesianLimitResponse), sizeof(ri::GetCartesianLimit::Response));
  std::array<double, 16> frame{};
  frame[13] = 0.25;
  const ri::GetCartesianLimit::Response wall(ri::GetCartesianLimit::Status::kInvalidArgumentRejected, {1, 2, 3}, frame, true);
  fci::GetCartesianLimitResponse limit;
  std::memcpy(static_cast<void*>(&limit), &wall, sizeof(limit));
  EXPECT_EQ(limit.status, 2);
  EXPECT_EQ(CSP_FCI_FIELD(limit, object_world_size)[2], 3.0);   // (at odd offsets: copied out)
  EXPECT_EQ(CSP_FCI_FIELD(limit, object_frame)[13], 0.25);
  EXPECT_EQ(limit.object_activation, 1);
#endif
}

// Every request's size as libfranka sends it: its Message<Request> (the header counts itself).
TEST(CSP_FCI_SUITE, RequestSizesAreWhatLibfrankaSends) {
  const auto message = [](auto* type) {
    using T = std::remove_pointer_t<decltype(type)>;
    return sizeof(typename T::template Message<typename T::Request>);
  };
  EXPECT_EQ(fci::request_size(fci::Command::kConnect, kVersion), message(static_cast<ri::Connect*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kMove, kVersion), message(static_cast<ri::Move*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kStopMove, kVersion), message(static_cast<ri::StopMove*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetCollisionBehavior, kVersion), message(static_cast<ri::SetCollisionBehavior*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetJointImpedance, kVersion), message(static_cast<ri::SetJointImpedance*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetCartesianImpedance, kVersion), message(static_cast<ri::SetCartesianImpedance*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetGuidingMode, kVersion), message(static_cast<ri::SetGuidingMode*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetEEToK, kVersion), message(static_cast<ri::SetEEToK*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetNEToEE, kVersion), message(static_cast<ri::SetNEToEE*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kSetLoad, kVersion), message(static_cast<ri::SetLoad*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kAutomaticErrorRecovery, kVersion), message(static_cast<ri::AutomaticErrorRecovery*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kLoadModelLibrary, kVersion), message(static_cast<ri::LoadModelLibrary*>(nullptr)));
#if CSP_FCI_VERSION == 5
  EXPECT_EQ(fci::request_size(fci::Command::kSetFilters, kVersion), message(static_cast<ri::SetFilters*>(nullptr)));
  EXPECT_EQ(fci::request_size(fci::Command::kGetCartesianLimit, kVersion), message(static_cast<ri::GetCartesianLimit*>(nullptr)));
#else
  EXPECT_THROW(fci::request_size(fci::Command::kSetFilters, kVersion), std::invalid_argument);
  EXPECT_THROW(fci::request_size(fci::Command::kGetCartesianLimit, kVersion), std::invalid_argument);
#endif
}

TEST(CSP_FCI_SUITE, CommandCodesAreLibfrankas) {
  const auto code = [](ri::Command c) { return static_cast<uint32_t>(c); };
  EXPECT_EQ(fci::command_code(fci::Command::kConnect, kVersion), code(ri::Command::kConnect));
  EXPECT_EQ(fci::command_code(fci::Command::kMove, kVersion), code(ri::Command::kMove));
  EXPECT_EQ(fci::command_code(fci::Command::kStopMove, kVersion), code(ri::Command::kStopMove));
  EXPECT_EQ(fci::command_code(fci::Command::kSetCollisionBehavior, kVersion), code(ri::Command::kSetCollisionBehavior));
  EXPECT_EQ(fci::command_code(fci::Command::kSetJointImpedance, kVersion), code(ri::Command::kSetJointImpedance));
  EXPECT_EQ(fci::command_code(fci::Command::kSetCartesianImpedance, kVersion), code(ri::Command::kSetCartesianImpedance));
  EXPECT_EQ(fci::command_code(fci::Command::kSetGuidingMode, kVersion), code(ri::Command::kSetGuidingMode));
  EXPECT_EQ(fci::command_code(fci::Command::kSetEEToK, kVersion), code(ri::Command::kSetEEToK));
  EXPECT_EQ(fci::command_code(fci::Command::kSetNEToEE, kVersion), code(ri::Command::kSetNEToEE));
  EXPECT_EQ(fci::command_code(fci::Command::kSetLoad, kVersion), code(ri::Command::kSetLoad));
  EXPECT_EQ(fci::command_code(fci::Command::kAutomaticErrorRecovery, kVersion), code(ri::Command::kAutomaticErrorRecovery));
  EXPECT_EQ(fci::command_code(fci::Command::kLoadModelLibrary, kVersion), code(ri::Command::kLoadModelLibrary));
#if CSP_FCI_VERSION == 5
  EXPECT_EQ(fci::command_code(fci::Command::kGetCartesianLimit, kVersion), code(ri::Command::kGetCartesianLimit));
  EXPECT_EQ(fci::command_code(fci::Command::kSetFilters, kVersion), code(ri::Command::kSetFilters));
#endif
  // Each code names one command, and a code past the last is none.
  for (uint32_t c = 0; c <= code(ri::Command::kLoadModelLibrary); ++c)
    EXPECT_EQ(fci::command_code(*fci::command_from_code(c, kVersion), kVersion), c);
  EXPECT_FALSE(fci::command_from_code(code(ri::Command::kLoadModelLibrary) + 1, kVersion));
}

TEST(CSP_FCI_SUITE, StatusCodesAreLibfrankas) {
  using S = fci::Status;
  const auto expect = [](fci::Command command, S status, auto vendor_status) {
    EXPECT_EQ(fci::status_code(command, status, kVersion), static_cast<uint8_t>(vendor_status))
        << fci::command_name(command) << " " << fci::status_name(status);
  };
  expect(fci::Command::kConnect, S::kIncompatibleLibraryVersion, ri::Connect::Status::kIncompatibleLibraryVersion);
  using M = ri::Move::Status;
  expect(fci::Command::kMove, S::kSuccess, M::kSuccess);
  expect(fci::Command::kMove, S::kMotionStarted, M::kMotionStarted);
  expect(fci::Command::kMove, S::kPreempted, M::kPreempted);
  expect(fci::Command::kMove, S::kCommandNotPossibleRejected, M::kCommandNotPossibleRejected);
  expect(fci::Command::kMove, S::kStartAtSingularPoseRejected, M::kStartAtSingularPoseRejected);
  expect(fci::Command::kMove, S::kInvalidArgumentRejected, M::kInvalidArgumentRejected);
  expect(fci::Command::kMove, S::kReflexAborted, M::kReflexAborted);
  expect(fci::Command::kMove, S::kEmergencyAborted, M::kEmergencyAborted);
  expect(fci::Command::kMove, S::kInputErrorAborted, M::kInputErrorAborted);
  expect(fci::Command::kMove, S::kAborted, M::kAborted);
  using StopMove = ri::StopMove::Status;
  expect(fci::Command::kStopMove, S::kCommandNotPossibleRejected, StopMove::kCommandNotPossibleRejected);
  expect(fci::Command::kStopMove, S::kEmergencyAborted, StopMove::kEmergencyAborted);
  expect(fci::Command::kStopMove, S::kReflexAborted, StopMove::kReflexAborted);
  expect(fci::Command::kStopMove, S::kAborted, StopMove::kAborted);
  using Setter = ri::SetLoad::Status;
  expect(fci::Command::kSetLoad, S::kCommandNotPossibleRejected, Setter::kCommandNotPossibleRejected);
  expect(fci::Command::kSetLoad, S::kInvalidArgumentRejected, Setter::kInvalidArgumentRejected);
  expect(fci::Command::kSetCollisionBehavior, S::kInvalidArgumentRejected, ri::SetCollisionBehavior::Status::kInvalidArgumentRejected);
  using Recovery = ri::AutomaticErrorRecovery::Status;
  expect(fci::Command::kAutomaticErrorRecovery, S::kCommandNotPossibleRejected, Recovery::kCommandNotPossibleRejected);
  expect(fci::Command::kAutomaticErrorRecovery, S::kManualErrorRecoveryRequiredRejected, Recovery::kManualErrorRecoveryRequiredRejected);
  expect(fci::Command::kAutomaticErrorRecovery, S::kReflexAborted, Recovery::kReflexAborted);
  expect(fci::Command::kAutomaticErrorRecovery, S::kAborted, Recovery::kAborted);
  expect(fci::Command::kLoadModelLibrary, S::kError, ri::LoadModelLibrary::Status::kError);
#if CSP_FCI_VERSION == 7
  expect(fci::Command::kMove, S::kPreemptedDueToActivatedSafetyFunctions, M::kPreemptedDueToActivatedSafetyFunctions);
  expect(fci::Command::kMove, S::kCommandRejectedDueToActivatedSafetyFunctions, M::kCommandRejectedDueToActivatedSafetyFunctions);
  expect(fci::Command::kStopMove, S::kCommandRejectedDueToActivatedSafetyFunctions, StopMove::kCommandRejectedDueToActivatedSafetyFunctions);
  expect(fci::Command::kSetLoad, S::kCommandRejectedDueToActivatedSafetyFunctions, Setter::kCommandRejectedDueToActivatedSafetyFunctions);
#else
  EXPECT_THROW(fci::status_code(fci::Command::kMove, S::kPreemptedDueToActivatedSafetyFunctions, kVersion), std::invalid_argument);
#endif
}

TEST(CSP_FCI_SUITE, TheModeCodesAreLibfrankas) {
  EXPECT_EQ(static_cast<uint32_t>(fci::MoveControllerMode::kExternalController),
            static_cast<uint32_t>(ri::Move::ControllerMode::kExternalController));
  EXPECT_EQ(static_cast<uint32_t>(fci::MoveMotionGeneratorMode::kCartesianVelocity),
            static_cast<uint32_t>(ri::Move::MotionGeneratorMode::kCartesianVelocity));
  EXPECT_EQ(static_cast<uint8_t>(fci::StateMotionGeneratorMode::kCartesianVelocity),
            static_cast<uint8_t>(ri::MotionGeneratorMode::kCartesianVelocity));
  EXPECT_EQ(static_cast<uint8_t>(fci::StateControllerMode::kOther), static_cast<uint8_t>(ri::ControllerMode::kOther));
  EXPECT_EQ(static_cast<uint8_t>(fci::StateRobotMode::kAutomaticErrorRecovery),
            static_cast<uint8_t>(ri::RobotMode::kAutomaticErrorRecovery));
  EXPECT_EQ(static_cast<uint8_t>(fci::StateRobotMode::kReflex), static_cast<uint8_t>(ri::RobotMode::kReflex));
#if CSP_FCI_VERSION == 7
  EXPECT_EQ(static_cast<uint32_t>(fci::MoveMotionGeneratorMode::kNone), static_cast<uint32_t>(ri::Move::MotionGeneratorMode::kNone));
  EXPECT_EQ(static_cast<uint8_t>(fci::StateMotionGeneratorMode::kNone), static_cast<uint8_t>(ri::MotionGeneratorMode::kNone));
#endif
}

// Each error flag where libfranka reads it (its Errors binds every field to its Error by name).
TEST(CSP_FCI_SUITE, TheErrorFlagsAreInTheResearchInterfacesOrder) {
  using E = ri::Error;
  using R = csp::rt::Error;
  const std::vector<std::pair<R, E>> pairs = {
      {R::joint_position_limits_violation, E::kJointPositionLimitsViolation},
      {R::cartesian_position_limits_violation, E::kCartesianPositionLimitsViolation},
      {R::self_collision_avoidance_violation, E::kSelfcollisionAvoidanceViolation},
      {R::joint_velocity_violation, E::kJointVelocityViolation},
      {R::cartesian_velocity_violation, E::kCartesianVelocityViolation},
      {R::force_control_safety_violation, E::kForceControlSafetyViolation},
      {R::joint_reflex, E::kJointReflex},
      {R::cartesian_reflex, E::kCartesianReflex},
      {R::max_goal_pose_deviation_violation, E::kMaxGoalPoseDeviationViolation},
      {R::max_path_pose_deviation_violation, E::kMaxPathPoseDeviationViolation},
      {R::cartesian_velocity_profile_safety_violation, E::kCartesianVelocityProfileSafetyViolation},
      {R::joint_position_motion_generator_start_pose_invalid, E::kJointPositionMotionGeneratorStartPoseInvalid},
      {R::joint_motion_generator_position_limits_violation, E::kJointMotionGeneratorPositionLimitsViolation},
      {R::joint_motion_generator_velocity_limits_violation, E::kJointMotionGeneratorVelocityLimitsViolation},
      {R::joint_motion_generator_velocity_discontinuity, E::kJointMotionGeneratorVelocityDiscontinuity},
      {R::joint_motion_generator_acceleration_discontinuity, E::kJointMotionGeneratorAccelerationDiscontinuity},
      {R::cartesian_position_motion_generator_start_pose_invalid, E::kCartesianPositionMotionGeneratorStartPoseInvalid},
      {R::cartesian_motion_generator_elbow_limit_violation, E::kCartesianMotionGeneratorElbowLimitViolation},
      {R::cartesian_motion_generator_velocity_limits_violation, E::kCartesianMotionGeneratorVelocityLimitsViolation},
      {R::cartesian_motion_generator_velocity_discontinuity, E::kCartesianMotionGeneratorVelocityDiscontinuity},
      {R::cartesian_motion_generator_acceleration_discontinuity, E::kCartesianMotionGeneratorAccelerationDiscontinuity},
      {R::cartesian_motion_generator_elbow_sign_inconsistent, E::kCartesianMotionGeneratorElbowSignInconsistent},
      {R::cartesian_motion_generator_start_elbow_invalid, E::kCartesianMotionGeneratorStartElbowInvalid},
      {R::cartesian_motion_generator_joint_position_limits_violation, E::kCartesianMotionGeneratorJointPositionLimitsViolation},
      {R::cartesian_motion_generator_joint_velocity_limits_violation, E::kCartesianMotionGeneratorJointVelocityLimitsViolation},
      {R::cartesian_motion_generator_joint_velocity_discontinuity, E::kCartesianMotionGeneratorJointVelocityDiscontinuity},
      {R::cartesian_motion_generator_joint_acceleration_discontinuity, E::kCartesianMotionGeneratorJointAccelerationDiscontinuity},
      {R::cartesian_position_motion_generator_invalid_frame, E::kCartesianPositionMotionGeneratorInvalidFrame},
      {R::force_controller_desired_force_tolerance_violation, E::kForceControllerDesiredForceToleranceViolation},
      {R::controller_torque_discontinuity, E::kControllerTorqueDiscontinuity},
      {R::start_elbow_sign_inconsistent, E::kStartElbowSignInconsistent},
      {R::communication_constraints_violation, E::kCommunicationConstraintsViolation},
      {R::power_limit_violation, E::kPowerLimitViolation},
      {R::joint_p2p_insufficient_torque_for_planning, E::kJointP2PInsufficientTorqueForPlanning},
      {R::tau_j_range_violation, E::kTauJRangeViolation},
      {R::instability_detected, E::kInstabilityDetection},
      {R::joint_move_in_wrong_direction, E::kJointMoveInWrongDirection},
      {R::cartesian_spline_motion_generator_violation, E::kCartesianSplineViolation},
      {R::joint_via_motion_generator_planning_joint_limit_violation, E::kJointViaPlanLimitViolation},
      {R::base_acceleration_initialization_timeout, E::kBaseAccelerationInitializationTimeout},
      {R::base_acceleration_invalid_reading, E::kBaseAccelerationInvalidReading},
  };
  ASSERT_EQ(pairs.size(), static_cast<std::size_t>(csp::rt::kNumErrors));
  EXPECT_EQ(static_cast<std::size_t>(E::kBaseAccelerationInvalidReading) + 1, pairs.size());
  for (const auto& [error, wire] : pairs)
    EXPECT_EQ(fci::wire_error_index(error), static_cast<int>(wire)) << csp::rt::error_name(error);
}

TEST(CSP_FCI_SUITE, TheRobotStateHasLibfrankasLayout) {
  using P = fci::RobotStatePacket;
  using V = ri::RobotState;
  EXPECT_EQ(sizeof(P), sizeof(V));
  CSP_EXPECT_FIELD(P, V, message_id);
  CSP_EXPECT_FIELD(P, V, O_T_EE);
  CSP_EXPECT_FIELD(P, V, O_T_EE_d);
  CSP_EXPECT_FIELD(P, V, F_T_EE);
  CSP_EXPECT_FIELD(P, V, EE_T_K);
  CSP_EXPECT_FIELD(P, V, F_T_NE);
  CSP_EXPECT_FIELD(P, V, NE_T_EE);
  CSP_EXPECT_FIELD(P, V, m_ee);
  CSP_EXPECT_FIELD(P, V, I_ee);
  CSP_EXPECT_FIELD(P, V, F_x_Cee);
  CSP_EXPECT_FIELD(P, V, m_load);
  CSP_EXPECT_FIELD(P, V, I_load);
  CSP_EXPECT_FIELD(P, V, F_x_Cload);
  CSP_EXPECT_FIELD(P, V, elbow);
  CSP_EXPECT_FIELD(P, V, elbow_d);
  CSP_EXPECT_FIELD(P, V, tau_J);
  CSP_EXPECT_FIELD(P, V, tau_J_d);
  CSP_EXPECT_FIELD(P, V, dtau_J);
  CSP_EXPECT_FIELD(P, V, q);
  CSP_EXPECT_FIELD(P, V, q_d);
  CSP_EXPECT_FIELD(P, V, dq);
  CSP_EXPECT_FIELD(P, V, dq_d);
  CSP_EXPECT_FIELD(P, V, ddq_d);
  CSP_EXPECT_FIELD(P, V, joint_contact);
  CSP_EXPECT_FIELD(P, V, cartesian_contact);
  CSP_EXPECT_FIELD(P, V, joint_collision);
  CSP_EXPECT_FIELD(P, V, cartesian_collision);
  CSP_EXPECT_FIELD(P, V, tau_ext_hat_filtered);
  CSP_EXPECT_FIELD(P, V, O_F_ext_hat_K);
  CSP_EXPECT_FIELD(P, V, K_F_ext_hat_K);
  CSP_EXPECT_FIELD(P, V, O_dP_EE_d);
  CSP_EXPECT_FIELD(P, V, O_ddP_O);
  CSP_EXPECT_FIELD(P, V, elbow_c);
  CSP_EXPECT_FIELD(P, V, delbow_c);
  CSP_EXPECT_FIELD(P, V, ddelbow_c);
  CSP_EXPECT_FIELD(P, V, O_T_EE_c);
  CSP_EXPECT_FIELD(P, V, O_dP_EE_c);
  CSP_EXPECT_FIELD(P, V, O_ddP_EE_c);
  CSP_EXPECT_FIELD(P, V, theta);
  CSP_EXPECT_FIELD(P, V, dtheta);
  CSP_EXPECT_FIELD(P, V, motion_generator_mode);
  CSP_EXPECT_FIELD(P, V, controller_mode);
  CSP_EXPECT_FIELD(P, V, errors);
  CSP_EXPECT_FIELD(P, V, reflex_reason);
  CSP_EXPECT_FIELD(P, V, robot_mode);
  CSP_EXPECT_FIELD(P, V, control_command_success_rate);
}

TEST(CSP_FCI_SUITE, TheRobotCommandHasLibfrankasLayout) {
  using M = fci::MotionGeneratorCommandPacket;
  using VM = ri::MotionGeneratorCommand;
  EXPECT_EQ(sizeof(M), sizeof(VM));
  CSP_EXPECT_FIELD(M, VM, q_c);
  CSP_EXPECT_FIELD(M, VM, dq_c);
  CSP_EXPECT_FIELD(M, VM, O_T_EE_c);
  CSP_EXPECT_FIELD(M, VM, O_dP_EE_c);
  CSP_EXPECT_FIELD(M, VM, elbow_c);
  CSP_EXPECT_FIELD(M, VM, valid_elbow);
  CSP_EXPECT_FIELD(M, VM, motion_generation_finished);
  EXPECT_EQ(fci::robot_command_size(kVersion), sizeof(ri::RobotCommand));
#if CSP_FCI_VERSION == 5
  using C = fci::RobotCommandPacketV5;
#else
  using C = fci::RobotCommandPacketV7;
  EXPECT_EQ(offsetof(C, torque_command_finished), offsetof(ri::RobotCommand, control) + offsetof(ri::ControllerCommand, torque_command_finished));
#endif
  EXPECT_EQ(sizeof(C), sizeof(ri::RobotCommand));
  CSP_EXPECT_FIELD(C, ri::RobotCommand, message_id);
  CSP_EXPECT_FIELD(C, ri::RobotCommand, motion);
  EXPECT_EQ(offsetof(C, tau_J_d), offsetof(ri::RobotCommand, control) + offsetof(ri::ControllerCommand, tau_J_d));

  // A command libfranka builds, decoded by CSP: every value where libfranka put it.
  alignas(8) ri::RobotCommand sent{};
  sent.message_id = 123456789;
  std::array<double, 7> tau{};
  for (int i = 0; i < 7; ++i) {
    sent.motion.q_c[i] = 0.1 * i;
    sent.motion.dq_c[i] = -0.2 * i;
    tau[i] = 1.5 + i;
  }
  // (tau_J_d lies at an odd offset: copied in)
  std::memcpy(reinterpret_cast<uint8_t*>(&sent) + offsetof(ri::RobotCommand, control) + offsetof(ri::ControllerCommand, tau_J_d),
              tau.data(), sizeof(tau));
  sent.motion.O_T_EE_c[12] = 0.42;
  sent.motion.O_dP_EE_c[5] = -0.3;
  sent.motion.elbow_c = {0.7, -1.0};
  sent.motion.valid_elbow = true;
  sent.motion.motion_generation_finished = true;
  const std::optional<fci::RobotCommandValues> got = fci::decode_robot_command(&sent, sizeof(sent), kVersion);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->message_id, 123456789u);
  EXPECT_EQ(got->q_c[6], 0.6000000000000001);
  EXPECT_EQ(got->dq_c[3], sent.motion.dq_c[3]);
  EXPECT_EQ(got->tau_J_d[4], 5.5);
  EXPECT_EQ(got->O_T_EE_c[12], 0.42);
  EXPECT_EQ(got->O_dP_EE_c[5], -0.3);
  EXPECT_EQ(got->elbow_c[1], -1.0);
  EXPECT_TRUE(got->valid_elbow);
  EXPECT_TRUE(got->motion_generation_finished);
  EXPECT_FALSE(got->torque_command_finished);
  EXPECT_FALSE(fci::decode_robot_command(&sent, sizeof(sent) - 1, kVersion));
}

// The hand's server (port 1338): version 3 in both libfranka versions.
TEST(CSP_FCI_SUITE, TheGripperMessagesAreLibfrankas) {
  namespace gripper = CSP_FCI_VENDOR::research_interface::gripper;
  EXPECT_EQ(fci::kGripperVersion, gripper::kVersion);
  EXPECT_EQ(sizeof(fci::GripperMessageHeader), sizeof(gripper::CommandHeader));
  CSP_EXPECT_FIELD(fci::GripperMessageHeader, gripper::CommandHeader, command);
  CSP_EXPECT_FIELD(fci::GripperMessageHeader, gripper::CommandHeader, command_id);
  CSP_EXPECT_FIELD(fci::GripperMessageHeader, gripper::CommandHeader, size);
  EXPECT_EQ(sizeof(fci::GripperConnectRequest), sizeof(gripper::Connect::Request));
  EXPECT_EQ(sizeof(fci::GripperConnectResponse), sizeof(gripper::Connect::Response));
  EXPECT_EQ(sizeof(fci::GripperStatusResponse), sizeof(gripper::Grasp::Response));
  EXPECT_EQ(sizeof(fci::GripperStatePacket), sizeof(gripper::GripperState));
  CSP_EXPECT_FIELD(fci::GripperStatePacket, gripper::GripperState, message_id);
  CSP_EXPECT_FIELD(fci::GripperStatePacket, gripper::GripperState, width);
  CSP_EXPECT_FIELD(fci::GripperStatePacket, gripper::GripperState, max_width);
  CSP_EXPECT_FIELD(fci::GripperStatePacket, gripper::GripperState, is_grasped);
  CSP_EXPECT_FIELD(fci::GripperStatePacket, gripper::GripperState, temperature);
  // A grasp as libfranka sends it (its epsilon is a struct of two doubles), read by CSP.
  using GraspMessage = gripper::Grasp::Message<gripper::Grasp::Request>;
  const GraspMessage sent(gripper::Grasp::Header(gripper::Command::kGrasp, 9, sizeof(GraspMessage)),
                          gripper::Grasp::Request(0.03, gripper::Grasp::GraspEpsilon(0.004, 0.005), 0.1, 40.0));
  EXPECT_EQ(fci::gripper_request_size(static_cast<uint16_t>(gripper::Command::kGrasp)), sizeof(GraspMessage));
  alignas(8) fci::GraspRequest grasp;
  std::memcpy(&grasp, reinterpret_cast<const uint8_t*>(&sent) + sizeof(fci::GripperMessageHeader), sizeof(grasp));
  EXPECT_EQ(grasp.width, 0.03);
  EXPECT_EQ(grasp.epsilon_inner, 0.004);
  EXPECT_EQ(grasp.epsilon_outer, 0.005);
  EXPECT_EQ(grasp.speed, 0.1);
  EXPECT_EQ(grasp.force, 40.0);
  using MoveMessage = gripper::Move::Message<gripper::Move::Request>;
  EXPECT_EQ(fci::gripper_request_size(static_cast<uint16_t>(gripper::Command::kMove)), sizeof(MoveMessage));
  EXPECT_EQ(fci::gripper_request_size(static_cast<uint16_t>(gripper::Command::kHoming)), sizeof(gripper::Homing::Message<gripper::Homing::Request>));
  EXPECT_EQ(fci::gripper_request_size(static_cast<uint16_t>(gripper::Command::kConnect)), sizeof(gripper::Connect::Message<gripper::Connect::Request>));
  EXPECT_EQ(static_cast<uint16_t>(fci::GripperStatus::kAborted), static_cast<uint16_t>(gripper::Grasp::Status::kAborted));
  EXPECT_EQ(static_cast<uint16_t>(fci::GripperStatus::kUnsuccessful), static_cast<uint16_t>(gripper::Grasp::Status::kUnsuccessful));
  EXPECT_EQ(static_cast<uint16_t>(fci::GripperCommand::kStop), static_cast<uint16_t>(gripper::Command::kStop));
}

// The Cobot Pump's server (port 1339): version 1 in both libfranka versions.
TEST(CSP_FCI_SUITE, TheVacuumGripperMessagesAreLibfrankas) {
  namespace vacuum = CSP_FCI_VENDOR::research_interface::vacuum_gripper;
  EXPECT_EQ(fci::kVacuumGripperVersion, vacuum::kVersion);
  EXPECT_EQ(fci::kVacuumGripperPort, vacuum::kCommandPort);
  EXPECT_EQ(sizeof(fci::GripperMessageHeader), sizeof(vacuum::CommandHeader));
  EXPECT_EQ(sizeof(fci::VacuumRequest), sizeof(vacuum::Vacuum::Request));
  CSP_EXPECT_FIELD(fci::VacuumRequest, vacuum::Vacuum::Request, vacuum);
  CSP_EXPECT_FIELD(fci::VacuumRequest, vacuum::Vacuum::Request, profile);
  EXPECT_EQ(offsetof(fci::VacuumRequest, timeout_ms), offsetof(vacuum::Vacuum::Request, timeout));
  EXPECT_EQ(sizeof(fci::DropOffRequest), sizeof(vacuum::DropOff::Request));
  EXPECT_EQ(sizeof(fci::VacuumStatePacket), sizeof(vacuum::VacuumGripperState));
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, message_id);
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, in_control_range);
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, part_present);
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, device_status);
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, actual_power);
  CSP_EXPECT_FIELD(fci::VacuumStatePacket, vacuum::VacuumGripperState, vacuum);
  // A vacuum request as libfranka builds it, read by CSP: its timeout is std::chrono::milliseconds.
  using Message = vacuum::Vacuum::Message<vacuum::Vacuum::Request>;
  const Message sent(vacuum::Vacuum::Header(vacuum::Command::kVacuum, 4, sizeof(Message)),
                     vacuum::Vacuum::Request(100, vacuum::Profile::kP2, std::chrono::milliseconds(1500)));
  EXPECT_EQ(fci::vacuum_request_size(static_cast<uint16_t>(vacuum::Command::kVacuum)), sizeof(Message));
  fci::VacuumRequest read;
  std::memcpy(&read, reinterpret_cast<const uint8_t*>(&sent) + sizeof(fci::GripperMessageHeader), sizeof(read));
  EXPECT_EQ(read.vacuum, 100);
  EXPECT_EQ(read.profile, 2);
  EXPECT_EQ(+read.timeout_ms, 1500);
  EXPECT_EQ(fci::vacuum_request_size(static_cast<uint16_t>(vacuum::Command::kDropOff)),
            sizeof(vacuum::DropOff::Message<vacuum::DropOff::Request>));
  EXPECT_EQ(static_cast<uint16_t>(fci::VacuumCommand::kStop), static_cast<uint16_t>(vacuum::Command::kStop));
}

#undef CSP_EXPECT_FIELD

}  // namespace
