#include "csp/fci/protocol.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace csp::fci {
namespace {

// The commands in code order (a command's code is its index).
const std::vector<Command>& commands(Version version) {
  static const std::vector<Command> version5 = {
      Command::kConnect,           Command::kMove,          Command::kStopMove,          Command::kGetCartesianLimit,
      Command::kSetCollisionBehavior, Command::kSetJointImpedance, Command::kSetCartesianImpedance,
      Command::kSetGuidingMode,    Command::kSetEEToK,      Command::kSetNEToEE,         Command::kSetLoad,
      Command::kSetFilters,        Command::kAutomaticErrorRecovery, Command::kLoadModelLibrary};
  static const std::vector<Command> version7 = {
      Command::kConnect,           Command::kMove,          Command::kStopMove,          Command::kSetCollisionBehavior,
      Command::kSetJointImpedance, Command::kSetCartesianImpedance, Command::kSetGuidingMode, Command::kSetEEToK,
      Command::kSetNEToEE,         Command::kSetLoad,       Command::kAutomaticErrorRecovery, Command::kLoadModelLibrary};
  if (version == kPandaVersion) return version5;
  if (version == kFr3Version) return version7;
  throw std::invalid_argument("FCI protocol version " + std::to_string(version) + " is not served");
}

// A command's statuses in code order (a status's code is its index). Version 7 inserted the
// "safety functions" statuses in the middle of several lists, so later codes moved.
std::vector<Status> statuses(Command command, Version version) {
  using S = Status;
  const bool v7 = version == kFr3Version;
  switch (command) {
    case Command::kConnect: return {S::kSuccess, S::kIncompatibleLibraryVersion};
    case Command::kMove:
      if (v7)
        return {S::kSuccess, S::kMotionStarted, S::kPreempted, S::kPreemptedDueToActivatedSafetyFunctions,
                S::kCommandRejectedDueToActivatedSafetyFunctions, S::kCommandNotPossibleRejected,
                S::kStartAtSingularPoseRejected, S::kInvalidArgumentRejected, S::kReflexAborted, S::kEmergencyAborted,
                S::kInputErrorAborted, S::kAborted};
      return {S::kSuccess, S::kMotionStarted, S::kPreempted, S::kCommandNotPossibleRejected,
              S::kStartAtSingularPoseRejected, S::kInvalidArgumentRejected, S::kReflexAborted, S::kEmergencyAborted,
              S::kInputErrorAborted, S::kAborted};
    case Command::kStopMove:
      if (v7)
        return {S::kSuccess, S::kCommandNotPossibleRejected, S::kCommandRejectedDueToActivatedSafetyFunctions,
                S::kEmergencyAborted, S::kReflexAborted, S::kAborted};
      return {S::kSuccess, S::kCommandNotPossibleRejected, S::kEmergencyAborted, S::kReflexAborted, S::kAborted};
    case Command::kAutomaticErrorRecovery:
      if (v7)
        return {S::kSuccess, S::kCommandNotPossibleRejected, S::kCommandRejectedDueToActivatedSafetyFunctions,
                S::kManualErrorRecoveryRequiredRejected, S::kReflexAborted, S::kEmergencyAborted, S::kAborted};
      return {S::kSuccess, S::kCommandNotPossibleRejected, S::kManualErrorRecoveryRequiredRejected,
              S::kReflexAborted, S::kEmergencyAborted, S::kAborted};
    case Command::kLoadModelLibrary: return {S::kSuccess, S::kError};
    default:   // the getters and setters
      if (v7)
        return {S::kSuccess, S::kCommandNotPossibleRejected, S::kInvalidArgumentRejected,
                S::kCommandRejectedDueToActivatedSafetyFunctions};
      return {S::kSuccess, S::kCommandNotPossibleRejected, S::kInvalidArgumentRejected};
  }
}

// The research interface's order of the error flags (libfranka-common's robot/error.h).
constexpr std::array<rt::Error, rt::kNumErrors> kWireErrorOrder = {
    rt::Error::joint_position_limits_violation,
    rt::Error::cartesian_position_limits_violation,
    rt::Error::self_collision_avoidance_violation,
    rt::Error::joint_velocity_violation,
    rt::Error::cartesian_velocity_violation,
    rt::Error::force_control_safety_violation,
    rt::Error::joint_reflex,
    rt::Error::cartesian_reflex,
    rt::Error::max_goal_pose_deviation_violation,
    rt::Error::max_path_pose_deviation_violation,
    rt::Error::cartesian_velocity_profile_safety_violation,
    rt::Error::joint_position_motion_generator_start_pose_invalid,
    rt::Error::joint_motion_generator_position_limits_violation,
    rt::Error::joint_motion_generator_velocity_limits_violation,
    rt::Error::joint_motion_generator_velocity_discontinuity,
    rt::Error::joint_motion_generator_acceleration_discontinuity,
    rt::Error::cartesian_position_motion_generator_start_pose_invalid,
    rt::Error::cartesian_motion_generator_elbow_limit_violation,
    rt::Error::cartesian_motion_generator_velocity_limits_violation,
    rt::Error::cartesian_motion_generator_velocity_discontinuity,
    rt::Error::cartesian_motion_generator_acceleration_discontinuity,
    rt::Error::cartesian_motion_generator_elbow_sign_inconsistent,
    rt::Error::cartesian_motion_generator_start_elbow_invalid,
    rt::Error::force_controller_desired_force_tolerance_violation,
    rt::Error::start_elbow_sign_inconsistent,
    rt::Error::communication_constraints_violation,
    rt::Error::power_limit_violation,
    rt::Error::cartesian_motion_generator_joint_position_limits_violation,
    rt::Error::cartesian_motion_generator_joint_velocity_limits_violation,
    rt::Error::cartesian_motion_generator_joint_velocity_discontinuity,
    rt::Error::cartesian_motion_generator_joint_acceleration_discontinuity,
    rt::Error::cartesian_position_motion_generator_invalid_frame,
    rt::Error::controller_torque_discontinuity,
    rt::Error::joint_p2p_insufficient_torque_for_planning,
    rt::Error::tau_j_range_violation,
    rt::Error::instability_detected,
    rt::Error::joint_move_in_wrong_direction,
    rt::Error::cartesian_spline_motion_generator_violation,
    rt::Error::joint_via_motion_generator_planning_joint_limit_violation,
    rt::Error::base_acceleration_initialization_timeout,
    rt::Error::base_acceleration_invalid_reading,
};

}  // namespace

int wire_error_index(rt::Error error) {
  // The inverse of kWireErrorOrder, made once: every state packet asks for all 41 flags.
  static const std::array<int, rt::kNumErrors> index = [] {
    std::array<int, rt::kNumErrors> inverse{};
    for (int wire = 0; wire < rt::kNumErrors; ++wire) inverse[static_cast<std::size_t>(kWireErrorOrder[wire])] = wire;
    return inverse;
  }();
  return index[static_cast<std::size_t>(error)];
}

const char* command_name(Command command) {
  switch (command) {
    case Command::kConnect: return "Connect";
    case Command::kMove: return "Move";
    case Command::kStopMove: return "StopMove";
    case Command::kGetCartesianLimit: return "GetCartesianLimit";
    case Command::kSetCollisionBehavior: return "SetCollisionBehavior";
    case Command::kSetJointImpedance: return "SetJointImpedance";
    case Command::kSetCartesianImpedance: return "SetCartesianImpedance";
    case Command::kSetGuidingMode: return "SetGuidingMode";
    case Command::kSetEEToK: return "SetEEToK";
    case Command::kSetNEToEE: return "SetNEToEE";
    case Command::kSetLoad: return "SetLoad";
    case Command::kSetFilters: return "SetFilters";
    case Command::kAutomaticErrorRecovery: return "AutomaticErrorRecovery";
    case Command::kLoadModelLibrary: return "LoadModelLibrary";
  }
  return "?";
}

const char* status_name(Status status) {
  switch (status) {
    case Status::kSuccess: return "Success";
    case Status::kMotionStarted: return "MotionStarted";
    case Status::kPreempted: return "Preempted";
    case Status::kPreemptedDueToActivatedSafetyFunctions: return "PreemptedDueToActivatedSafetyFunctions";
    case Status::kCommandRejectedDueToActivatedSafetyFunctions: return "CommandRejectedDueToActivatedSafetyFunctions";
    case Status::kCommandNotPossibleRejected: return "CommandNotPossibleRejected";
    case Status::kStartAtSingularPoseRejected: return "StartAtSingularPoseRejected";
    case Status::kInvalidArgumentRejected: return "InvalidArgumentRejected";
    case Status::kReflexAborted: return "ReflexAborted";
    case Status::kEmergencyAborted: return "EmergencyAborted";
    case Status::kInputErrorAborted: return "InputErrorAborted";
    case Status::kAborted: return "Aborted";
    case Status::kManualErrorRecoveryRequiredRejected: return "ManualErrorRecoveryRequiredRejected";
    case Status::kIncompatibleLibraryVersion: return "IncompatibleLibraryVersion";
    case Status::kError: return "Error";
  }
  return "?";
}

std::optional<Command> command_from_code(uint32_t code, Version version) {
  const std::vector<Command>& list = commands(version);
  if (code >= list.size()) return std::nullopt;
  return list[code];
}

uint32_t command_code(Command command, Version version) {
  const std::vector<Command>& list = commands(version);
  const auto found = std::find(list.begin(), list.end(), command);
  if (found == list.end())
    throw std::invalid_argument(std::string(command_name(command)) + " is not a command of FCI version " + std::to_string(version));
  return static_cast<uint32_t>(found - list.begin());
}

uint8_t status_code(Command command, Status status, Version version) {
  commands(version);   // a version CSP serves
  const std::vector<Status> list = statuses(command, version);
  const auto found = std::find(list.begin(), list.end(), status);
  if (found == list.end())
    throw std::invalid_argument(std::string(command_name(command)) + " has no status " + status_name(status) +
                                " in FCI version " + std::to_string(version));
  return static_cast<uint8_t>(found - list.begin());
}

std::size_t robot_command_size(Version version) {
  return version == kPandaVersion ? sizeof(RobotCommandPacketV5) : sizeof(RobotCommandPacketV7);
}

std::optional<RobotCommandValues> decode_robot_command(const void* data, std::size_t size, Version version) {
  if (size != robot_command_size(version)) return std::nullopt;
  RobotCommandPacketV7 packet{};
  std::memcpy(&packet, data, size);   // version 5 lacks only the last byte: torque_command_finished stays 0
  RobotCommandValues v;
  v.message_id = CSP_FCI_FIELD(packet, message_id);
  v.q_c = CSP_FCI_FIELD(packet, motion.q_c);
  v.dq_c = CSP_FCI_FIELD(packet, motion.dq_c);
  v.O_T_EE_c = CSP_FCI_FIELD(packet, motion.O_T_EE_c);
  v.O_dP_EE_c = CSP_FCI_FIELD(packet, motion.O_dP_EE_c);
  v.elbow_c = CSP_FCI_FIELD(packet, motion.elbow_c);
  v.valid_elbow = CSP_FCI_FIELD(packet, motion.valid_elbow);
  v.motion_generation_finished = CSP_FCI_FIELD(packet, motion.motion_generation_finished);
  v.tau_J_d = CSP_FCI_FIELD(packet, tau_J_d);
  v.torque_command_finished = CSP_FCI_FIELD(packet, torque_command_finished) != 0;
  return v;
}

std::size_t request_size(Command command, Version version) {
  command_code(command, version);   // a command of this version
  const auto with = [](std::size_t payload) { return sizeof(MessageHeader) + payload; };
  switch (command) {
    case Command::kConnect: return with(sizeof(ConnectRequest));
    case Command::kMove: return with(sizeof(MoveRequest));
    case Command::kStopMove: return with(0);
    case Command::kGetCartesianLimit: return with(sizeof(GetCartesianLimitRequest));
    case Command::kSetCollisionBehavior: return with(sizeof(CollisionBehaviorRequest));
    case Command::kSetJointImpedance: return with(sizeof(JointImpedanceRequest));
    case Command::kSetCartesianImpedance: return with(sizeof(CartesianImpedanceRequest));
    case Command::kSetGuidingMode: return with(sizeof(GuidingModeRequest));
    case Command::kSetEEToK: return with(sizeof(EEToKRequest));
    case Command::kSetNEToEE: return with(sizeof(NEToEERequest));
    case Command::kSetLoad: return with(sizeof(LoadRequest));
    case Command::kSetFilters: return with(sizeof(FiltersRequest));
    case Command::kAutomaticErrorRecovery: return with(0);
    case Command::kLoadModelLibrary: return with(sizeof(LoadModelLibraryRequest));
  }
  return 0;
}

const char* gripper_command_name(GripperCommand command) {
  switch (command) {
    case GripperCommand::kConnect: return "Connect";
    case GripperCommand::kHoming: return "Homing";
    case GripperCommand::kGrasp: return "Grasp";
    case GripperCommand::kMove: return "Move";
    case GripperCommand::kStop: return "Stop";
  }
  return "?";
}

const char* vacuum_command_name(VacuumCommand command) {
  switch (command) {
    case VacuumCommand::kConnect: return "Connect";
    case VacuumCommand::kVacuum: return "Vacuum";
    case VacuumCommand::kDropOff: return "DropOff";
    case VacuumCommand::kStop: return "Stop";
  }
  return "?";
}

std::size_t vacuum_request_size(uint16_t command) {
  const auto with = [](std::size_t payload) { return sizeof(GripperMessageHeader) + payload; };
  switch (static_cast<VacuumCommand>(command)) {
    case VacuumCommand::kConnect: return with(sizeof(GripperConnectRequest));
    case VacuumCommand::kVacuum: return with(sizeof(VacuumRequest));
    case VacuumCommand::kDropOff: return with(sizeof(DropOffRequest));
    case VacuumCommand::kStop: return with(0);
  }
  return 0;
}

std::size_t gripper_request_size(uint16_t command) {
  const auto with = [](std::size_t payload) { return sizeof(GripperMessageHeader) + payload; };
  switch (static_cast<GripperCommand>(command)) {
    case GripperCommand::kConnect: return with(sizeof(GripperConnectRequest));
    case GripperCommand::kHoming: return with(0);
    case GripperCommand::kGrasp: return with(sizeof(GraspRequest));
    case GripperCommand::kMove: return with(sizeof(GripperMoveRequest));
    case GripperCommand::kStop: return with(0);
  }
  return 0;
}

}  // namespace csp::fci
