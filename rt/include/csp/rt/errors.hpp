// The robot's error flags with libfranka's names (franka::Errors, libfranka 0.15): what a reflex
// latches in RobotState::current_errors and last_motion_errors.
#pragma once

#include <array>
#include <ostream>
#include <string>

namespace csp::rt {

// X(name): every flag of franka::Errors, in libfranka's order.
#define CSP_FRANKA_ERRORS(X)                                    \
  X(joint_position_limits_violation)                            \
  X(cartesian_position_limits_violation)                        \
  X(self_collision_avoidance_violation)                         \
  X(joint_velocity_violation)                                   \
  X(cartesian_velocity_violation)                               \
  X(force_control_safety_violation)                             \
  X(joint_reflex)                                               \
  X(cartesian_reflex)                                           \
  X(max_goal_pose_deviation_violation)                          \
  X(max_path_pose_deviation_violation)                          \
  X(cartesian_velocity_profile_safety_violation)                \
  X(joint_position_motion_generator_start_pose_invalid)         \
  X(joint_motion_generator_position_limits_violation)           \
  X(joint_motion_generator_velocity_limits_violation)           \
  X(joint_motion_generator_velocity_discontinuity)              \
  X(joint_motion_generator_acceleration_discontinuity)          \
  X(cartesian_position_motion_generator_start_pose_invalid)     \
  X(cartesian_motion_generator_elbow_limit_violation)           \
  X(cartesian_motion_generator_velocity_limits_violation)       \
  X(cartesian_motion_generator_velocity_discontinuity)          \
  X(cartesian_motion_generator_acceleration_discontinuity)      \
  X(cartesian_motion_generator_elbow_sign_inconsistent)         \
  X(cartesian_motion_generator_start_elbow_invalid)             \
  X(cartesian_motion_generator_joint_position_limits_violation) \
  X(cartesian_motion_generator_joint_velocity_limits_violation) \
  X(cartesian_motion_generator_joint_velocity_discontinuity)    \
  X(cartesian_motion_generator_joint_acceleration_discontinuity) \
  X(cartesian_position_motion_generator_invalid_frame)          \
  X(force_controller_desired_force_tolerance_violation)         \
  X(controller_torque_discontinuity)                            \
  X(start_elbow_sign_inconsistent)                              \
  X(communication_constraints_violation)                        \
  X(power_limit_violation)                                      \
  X(joint_p2p_insufficient_torque_for_planning)                 \
  X(tau_j_range_violation)                                      \
  X(instability_detected)                                       \
  X(joint_move_in_wrong_direction)

enum class Error {
#define CSP_ENUM_ENTRY(name) name,
  CSP_FRANKA_ERRORS(CSP_ENUM_ENTRY)
#undef CSP_ENUM_ENTRY
};

inline constexpr int kNumErrors = 37;

// libfranka's name of an error, e.g. "joint_velocity_violation".
const char* error_name(Error error);

class Errors {
 public:
  Errors() = default;
  explicit Errors(const std::array<bool, kNumErrors>& errors) : errors_(errors) {}

  const std::array<bool, kNumErrors>& errors() const { return errors_; }
  bool has(Error error) const { return errors_[static_cast<int>(error)]; }
  void set(Error error) { errors_[static_cast<int>(error)] = true; }
  void merge(const Errors& other) {
    for (int i = 0; i < kNumErrors; ++i) errors_[i] = errors_[i] || other.errors_[i];
  }

  explicit operator bool() const noexcept;
  // "[name_1, name_2]" as libfranka prints it; "[]" without errors.
  explicit operator std::string() const;

#define CSP_ACCESSOR(name) \
  const bool& name() const { return errors_[static_cast<int>(Error::name)]; }
  CSP_FRANKA_ERRORS(CSP_ACCESSOR)
#undef CSP_ACCESSOR

  bool operator==(const Errors&) const = default;

 private:
  std::array<bool, kNumErrors> errors_{};
};

// Streams the active errors as a JSON array of names.
std::ostream& operator<<(std::ostream& out, const Errors& errors);

}  // namespace csp::rt
