// The FCI research interface on the wire, as the robot speaks it (docs/fci.md): the TCP messages of
// the command port (1337) and the UDP state and command packets of the 1 kHz exchange, for the two
// protocol versions CSP serves: 5 (libfranka 0.9.x, the Panda) and 7 (libfranka 0.13.x, the FR3).
//
// Written from libfranka's research-interface headers (common/include/research_interface/robot in
// ../shared/vendor), not copied: CSP's own structs, every field in the robot's order, packed as the
// robot packs them (little endian, no padding). tests/fci/test_fci_protocol_v*.cpp compile each
// version's vendored header beside these and check size, offset and code of every field and value.
//
// The versions differ in command codes (5 has GetCartesianLimit and SetFilters), in some status
// codes (7 adds the "safety functions" statuses in the middle of the enums) and in the controller
// command (7 adds torque_command_finished). Both use the same robot state.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>

#include "csp/rt/errors.hpp"
#include "research_interface/robot/rbk_types.h"

namespace csp::fci {

using Version = uint16_t;
inline constexpr Version kPandaVersion = 5;   // libfranka 0.9.x (Panda system >= 4.2.1)
inline constexpr Version kFr3Version = 7;     // libfranka 0.13.x (FR3; its earlier releases speak other versions)
inline constexpr uint16_t kCommandPort = 1337;
inline constexpr uint16_t kGripperPort = 1338;

// The commands of the command port, by name; their codes depend on the version (wire_code).
enum class Command {
  kConnect,
  kMove,
  kStopMove,
  kGetCartesianLimit,   // version 5 only
  kSetCollisionBehavior,
  kSetJointImpedance,
  kSetCartesianImpedance,
  kSetGuidingMode,
  kSetEEToK,
  kSetNEToEE,
  kSetLoad,
  kSetFilters,          // version 5 only
  kAutomaticErrorRecovery,
  kLoadModelLibrary,
};
const char* command_name(Command command);
// The command a code stands for in `version`; nullopt for a code the version does not have.
std::optional<Command> command_from_code(uint32_t code, Version version);
uint32_t command_code(Command command, Version version);   // throws std::invalid_argument if absent

// Statuses of the responses, by name (the union over the versions); status_code() gives a
// command's code for one in a version (throws std::invalid_argument if it has none).
enum class Status {
  kSuccess,
  kMotionStarted,
  kPreempted,
  kPreemptedDueToActivatedSafetyFunctions,
  kCommandRejectedDueToActivatedSafetyFunctions,
  kCommandNotPossibleRejected,
  kStartAtSingularPoseRejected,
  kInvalidArgumentRejected,
  kReflexAborted,
  kEmergencyAborted,
  kInputErrorAborted,
  kAborted,
  kManualErrorRecoveryRequiredRejected,
  kIncompatibleLibraryVersion,
  kError,
};
const char* status_name(Status status);
uint8_t status_code(Command command, Status status, Version version);

#pragma pack(push, 1)

// Every TCP message begins with this; `size` counts the whole message, header included.
struct MessageHeader {
  uint32_t command = 0;
  uint32_t command_id = 0;
  uint32_t size = 0;
};

struct ConnectRequest {
  Version version = 0;
  uint16_t udp_port = 0;   // where the client receives the robot state
};
struct ConnectResponse {
  uint8_t status = 0;
  Version version = 0;     // the robot's
};

// Move: which controller tracks which motion generator (the codes of the Move request).
enum class MoveControllerMode : uint32_t { kJointImpedance, kCartesianImpedance, kExternalController };
enum class MoveMotionGeneratorMode : uint32_t { kJointPosition, kJointVelocity, kCartesianPosition, kCartesianVelocity, kNone };
struct Deviation {
  double translation = 0.0, rotation = 0.0, elbow = 0.0;
};
struct MoveRequest {
  uint32_t controller_mode = 0;
  uint32_t motion_generator_mode = 0;
  Deviation maximum_path_deviation, maximum_goal_pose_deviation;
};

struct CollisionBehaviorRequest {
  std::array<double, 7> lower_torque_thresholds_acceleration, upper_torque_thresholds_acceleration;
  std::array<double, 7> lower_torque_thresholds_nominal, upper_torque_thresholds_nominal;
  std::array<double, 6> lower_force_thresholds_acceleration, upper_force_thresholds_acceleration;
  std::array<double, 6> lower_force_thresholds_nominal, upper_force_thresholds_nominal;
};
struct JointImpedanceRequest {
  std::array<double, 7> K_theta;
};
struct CartesianImpedanceRequest {
  std::array<double, 6> K_x;
};
struct GuidingModeRequest {
  std::array<uint8_t, 6> guiding_mode;   // bools
  uint8_t nullspace;
};
struct EEToKRequest {
  std::array<double, 16> EE_T_K;
};
struct NEToEERequest {
  std::array<double, 16> NE_T_EE;
};
struct LoadRequest {
  double m_load;
  std::array<double, 3> F_x_Cload;
  std::array<double, 9> I_load;
};
struct FiltersRequest {   // version 5
  double joint_position_filter_frequency, joint_velocity_filter_frequency;
  double cartesian_position_filter_frequency, cartesian_velocity_filter_frequency;
  double controller_filter_frequency;
};
struct GetCartesianLimitRequest {   // version 5
  int32_t id;
};
struct GetCartesianLimitResponse {
  uint8_t status;
  std::array<double, 3> object_world_size;
  std::array<double, 16> object_frame;
  uint8_t object_activation;
};
struct LoadModelLibraryRequest {
  uint8_t architecture;   // 0 x64, 1 x86, 2 ARM, 3 ARM64
  uint8_t system;         // 0 Linux, 1 Windows
};
// Every other response is its status alone; LoadModelLibrary's is followed by the library's bytes.
struct StatusResponse {
  uint8_t status = 0;
};

#pragma pack(pop)

// The UDP robot state (one a millisecond) and the motion part of the command answering it: the same
// in both versions, and the same declarations programs written for libfranka include
// (rt/franka's research_interface/robot/rbk_types.h, one home for the layout). The state's mode
// codes are its own, not the Move request's.
using RobotStatePacket = research_interface::robot::RobotState;
using MotionGeneratorCommandPacket = research_interface::robot::MotionGeneratorCommand;
using StateMotionGeneratorMode = research_interface::robot::MotionGeneratorMode;
using StateControllerMode = research_interface::robot::ControllerMode;
using StateRobotMode = research_interface::robot::RobotMode;

#pragma pack(push, 1)
// The UDP command answering a state (its message_id).
struct RobotCommandPacketV5 {
  uint64_t message_id;
  MotionGeneratorCommandPacket motion;
  std::array<double, 7> tau_J_d;
};
struct RobotCommandPacketV7 {
  uint64_t message_id;
  MotionGeneratorCommandPacket motion;
  std::array<double, 7> tau_J_d;
  uint8_t torque_command_finished;
};

#pragma pack(pop)

// --- The Franka Hand's server (port 1338), research-interface gripper version 3 in both libfranka
// 0.9 and 0.13: its own header (a 16-bit command code), requests answered when the command ends,
// and a UDP state message about every 100 ms (rt::HandSettings::state_period).
inline constexpr uint16_t kGripperVersion = 3;
enum class GripperCommand : uint16_t { kConnect, kHoming, kGrasp, kMove, kStop };
enum class GripperStatus : uint16_t { kSuccess, kFail, kUnsuccessful, kAborted };   // Connect: 1 is a refused version
const char* gripper_command_name(GripperCommand command);

#pragma pack(push, 1)
struct GripperMessageHeader {
  uint16_t command = 0;
  uint32_t command_id = 0;
  uint32_t size = 0;
};
struct GripperConnectRequest {
  uint16_t version = 0;
  uint16_t udp_port = 0;
};
struct GripperConnectResponse {
  uint16_t status = 0;
  uint16_t version = 0;
};
struct GraspRequest {
  double width, epsilon_inner, epsilon_outer, speed, force;
};
struct GripperMoveRequest {
  double width, speed;
};
struct GripperStatusResponse {
  uint16_t status = 0;
};
struct GripperStatePacket {
  uint32_t message_id;
  double width, max_width;
  uint8_t is_grasped;
  uint16_t temperature;
};
#pragma pack(pop)

// The size of a gripper request message (header included); 0 for a code that is no command.
std::size_t gripper_request_size(uint16_t command);

// --- The Cobot Pump's server (port 1339), research-interface vacuum gripper version 1 in both
// libfranka 0.9 and 0.13: the hand's message shape (the same header and statuses), its own commands.
inline constexpr uint16_t kVacuumGripperVersion = 1;
inline constexpr uint16_t kVacuumGripperPort = 1339;
enum class VacuumCommand : uint16_t { kConnect, kVacuum, kDropOff, kStop };
const char* vacuum_command_name(VacuumCommand command);

#pragma pack(push, 1)
struct VacuumRequest {
  uint8_t vacuum;       // setpoint [10 mbar]
  uint8_t profile;      // production setup profile P0..P3
  int64_t timeout_ms;   // std::chrono::milliseconds
};
struct DropOffRequest {
  int64_t timeout_ms;
};
struct VacuumStatePacket {
  uint32_t message_id;
  uint8_t in_control_range, part_detached, part_present;
  uint8_t device_status;   // 0 green, 1 yellow, 2 orange, 3 red
  int32_t actual_power;    // [%]
  int32_t vacuum;          // [mbar]
};
#pragma pack(pop)

// The size of a vacuum gripper request message (header included); 0 for a code that is no command.
std::size_t vacuum_request_size(uint16_t command);

// The robot state's 41 error flags (errors, reflex_reason) are in the research interface's own
// order, which is not franka::Errors' field order (libfranka maps each field to its flag by name):
// the flag of `error` is at wire_error_index(error).
int wire_error_index(rt::Error error);

// The size of a command packet in `version`.
std::size_t robot_command_size(Version version);
// A field of a packed wire struct copied out as a value of its type. The wire puts fields where it
// will (a command's tau_J_d at an odd offset), so reading one through a reference of its type, as
// passing it to a function or calling an std::array member does, would be undefined behaviour.
template <typename Field>
Field unaligned_field(const void* packet, std::size_t offset) {
  Field value;
  std::memcpy(&value, static_cast<const unsigned char*>(packet) + offset, sizeof(Field));
  return value;
}
#define CSP_FCI_FIELD(packet, member)                                           \
  ::csp::fci::unaligned_field<std::remove_cvref_t<decltype((packet).member)>>( \
      &(packet), offsetof(std::remove_cvref_t<decltype(packet)>, member))

// A command packet of either version decoded into aligned values (torque_command_finished: false
// in version 5).
struct RobotCommandValues {
  uint64_t message_id = 0;
  std::array<double, 7> q_c{}, dq_c{};
  std::array<double, 16> O_T_EE_c{};
  std::array<double, 6> O_dP_EE_c{};
  std::array<double, 2> elbow_c{};
  bool valid_elbow = false, motion_generation_finished = false;
  std::array<double, 7> tau_J_d{};
  bool torque_command_finished = false;
};
// Returns nullopt if `size` is not the version's packet size.
std::optional<RobotCommandValues> decode_robot_command(const void* data, std::size_t size, Version version);

// The size of a request message (header included) of `command` in `version`.
std::size_t request_size(Command command, Version version);

}  // namespace csp::fci
