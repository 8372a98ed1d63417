// franka::Model: the robot's own dynamic model (what its firmware believes, not the emulated
// plant), libfranka 0.15's class and signatures. Matrices are column-major arrays; Jacobians are
// 6x7 with the linear rows first. Made by Robot::loadModel; the model lives behind Impl, so this
// class's layout does not depend on the flags a program is compiled with. Self-contained, C++14.
#pragma once

#include <array>
#include <memory>

#include "franka/robot.h"
#include "franka/robot_state.h"

namespace franka {

enum class Frame { kJoint1, kJoint2, kJoint3, kJoint4, kJoint5, kJoint6, kJoint7, kFlange, kEndEffector, kStiffness };

// Frame after `frame` (for loops over frames, as in libfranka's print_joint_poses).
Frame operator++(Frame& frame, int /* dummy */) noexcept;

class Model {
 public:
  class Impl;
  // CSP: made by Robot::loadModel.
  explicit Model(std::unique_ptr<Impl> impl) noexcept;
  Model(Model&& model) noexcept;
  Model& operator=(Model&& model) noexcept;
  ~Model() noexcept;

  // Pose of `frame` in the base frame, column-major 4x4.
  std::array<double, 16> pose(Frame frame, const franka::RobotState& robot_state) const;
  std::array<double, 16> pose(Frame frame, const std::array<double, 7>& q,
                              const std::array<double, 16>& F_T_EE,   // NOLINT(readability-identifier-naming)
                              const std::array<double, 16>& EE_T_K)   // NOLINT(readability-identifier-naming)
      const;

  // Jacobian of `frame` with both rows in `frame` (bodyJacobian) or in the base frame (zeroJacobian).
  std::array<double, 42> bodyJacobian(Frame frame, const franka::RobotState& robot_state) const;
  std::array<double, 42> bodyJacobian(Frame frame, const std::array<double, 7>& q,
                                      const std::array<double, 16>& F_T_EE,   // NOLINT(readability-identifier-naming)
                                      const std::array<double, 16>& EE_T_K)   // NOLINT(readability-identifier-naming)
      const;
  std::array<double, 42> zeroJacobian(Frame frame, const franka::RobotState& robot_state) const;
  std::array<double, 42> zeroJacobian(Frame frame, const std::array<double, 7>& q,
                                      const std::array<double, 16>& F_T_EE,   // NOLINT(readability-identifier-naming)
                                      const std::array<double, 16>& EE_T_K)   // NOLINT(readability-identifier-naming)
      const;

  // Mass matrix M(q), column-major 7x7, with the total load on the flange (end effector and load:
  // RobotState::m_total, F_x_Ctotal, I_total). A load no rigid body can have (negative mass, an
  // inertia that is not physical) gives NaN values, which control() then refuses.
  std::array<double, 49> mass(const franka::RobotState& robot_state) const noexcept;
  std::array<double, 49> mass(const std::array<double, 7>& q,
                              const std::array<double, 9>& I_total,   // NOLINT(readability-identifier-naming)
                              double m_total,
                              const std::array<double, 3>& F_x_Ctotal)   // NOLINT(readability-identifier-naming)
      const noexcept;

  // Coriolis and centrifugal torques C(q, dq) dq [N m].
  std::array<double, 7> coriolis(const franka::RobotState& robot_state) const noexcept;
  std::array<double, 7> coriolis(const std::array<double, 7>& q, const std::array<double, 7>& dq,
                                 const std::array<double, 9>& I_total,   // NOLINT(readability-identifier-naming)
                                 double m_total,
                                 const std::array<double, 3>& F_x_Ctotal)   // NOLINT(readability-identifier-naming)
      const noexcept;

  // Gravity torques g(q) that hold the arm still [N m], for gravity `gravity_earth` [m/s^2].
  std::array<double, 7> gravity(const std::array<double, 7>& q, double m_total,
                                const std::array<double, 3>& F_x_Ctotal,   // NOLINT(readability-identifier-naming)
                                const std::array<double, 3>& gravity_earth = {{0., 0., -9.81}}) const noexcept;
  std::array<double, 7> gravity(const franka::RobotState& robot_state,
                                const std::array<double, 3>& gravity_earth) const noexcept;
  std::array<double, 7> gravity(const franka::RobotState& robot_state) const noexcept;

  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace franka
