// franka::Errors: the robot's error flags, libfranka 0.15's struct (41 flags, each a `const bool&`
// member such as errors.joint_reflex). Self-contained: a libfranka program includes it as it is.
#pragma once

#include <array>
#include <cstddef>
#include <ostream>
#include <string>

// X(name): every flag in libfranka's order. The one list of the flags: the members below, CSP's
// error enum (csp/rt/errors.hpp) and every writer of error names are generated from it.
#define CSP_FRANKA_ERRORS(X)                                      \
  X(joint_position_limits_violation)                              \
  X(cartesian_position_limits_violation)                          \
  X(self_collision_avoidance_violation)                           \
  X(joint_velocity_violation)                                     \
  X(cartesian_velocity_violation)                                 \
  X(force_control_safety_violation)                               \
  X(joint_reflex)                                                 \
  X(cartesian_reflex)                                             \
  X(max_goal_pose_deviation_violation)                            \
  X(max_path_pose_deviation_violation)                            \
  X(cartesian_velocity_profile_safety_violation)                  \
  X(joint_position_motion_generator_start_pose_invalid)           \
  X(joint_motion_generator_position_limits_violation)             \
  X(joint_motion_generator_velocity_limits_violation)             \
  X(joint_motion_generator_velocity_discontinuity)                \
  X(joint_motion_generator_acceleration_discontinuity)            \
  X(cartesian_position_motion_generator_start_pose_invalid)       \
  X(cartesian_motion_generator_elbow_limit_violation)             \
  X(cartesian_motion_generator_velocity_limits_violation)         \
  X(cartesian_motion_generator_velocity_discontinuity)            \
  X(cartesian_motion_generator_acceleration_discontinuity)        \
  X(cartesian_motion_generator_elbow_sign_inconsistent)           \
  X(cartesian_motion_generator_start_elbow_invalid)               \
  X(cartesian_motion_generator_joint_position_limits_violation)   \
  X(cartesian_motion_generator_joint_velocity_limits_violation)   \
  X(cartesian_motion_generator_joint_velocity_discontinuity)      \
  X(cartesian_motion_generator_joint_acceleration_discontinuity)  \
  X(cartesian_position_motion_generator_invalid_frame)            \
  X(force_controller_desired_force_tolerance_violation)           \
  X(controller_torque_discontinuity)                              \
  X(start_elbow_sign_inconsistent)                                \
  X(communication_constraints_violation)                          \
  X(power_limit_violation)                                        \
  X(joint_p2p_insufficient_torque_for_planning)                   \
  X(tau_j_range_violation)                                        \
  X(instability_detected)                                         \
  X(joint_move_in_wrong_direction)                                \
  X(cartesian_spline_motion_generator_violation)                  \
  X(joint_via_motion_generator_planning_joint_limit_violation)    \
  X(base_acceleration_initialization_timeout)                     \
  X(base_acceleration_invalid_reading)

namespace franka {

struct Errors {
 private:
  std::array<bool, 41> errors_{};

 public:
  // No error set.
  Errors();
  Errors(const Errors& other);
  Errors& operator=(Errors other);
  // The flags in libfranka's order.
  Errors(const std::array<bool, 41>& errors);   // NOLINT(google-explicit-constructor): implicit as in libfranka

  // Whether any flag is set.
  explicit operator bool() const noexcept;
  // The set flags' names, e.g. "[joint_reflex, cartesian_reflex]"; "[]" without errors.
  explicit operator std::string() const;

  // One flag per error, true while it is set.
#define CSP_FRANKA_ERROR_MEMBER(name) const bool& name;
  CSP_FRANKA_ERRORS(CSP_FRANKA_ERROR_MEMBER)
#undef CSP_FRANKA_ERROR_MEMBER
};

// Streams the set flags as a JSON array of names, e.g. ["joint_reflex"].
std::ostream& operator<<(std::ostream& ostream, const Errors& errors);

}  // namespace franka
