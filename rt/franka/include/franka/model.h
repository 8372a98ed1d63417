// franka::Model: the robot's own dynamic model (what its firmware believes, not the emulated
// plant), with libfranka's signatures. Matrices are column-major arrays; Jacobians are 6x7 with
// the linear rows first.
#pragma once

#include <array>

#include "csp/dynamics/model.hpp"
#include "franka/robot_state.h"

namespace franka {

enum class Frame { kJoint1, kJoint2, kJoint3, kJoint4, kJoint5, kJoint6, kJoint7, kFlange, kEndEffector, kStiffness };

// Frame after `frame` (for loops over frames, as in libfranka's examples).
Frame operator++(Frame& frame, int /* dummy */) noexcept;

class Model {
 public:
  // CSP: built by Robot::loadModel from the robot's internal model.
  explicit Model(const csp::Model& robot_model);

  // Pose of `frame` in the base frame, column-major 4x4.
  std::array<double, 16> pose(Frame frame, const RobotState& robot_state) const;
  std::array<double, 16> pose(Frame frame, const std::array<double, 7>& q, const std::array<double, 16>& F_T_EE,
                              const std::array<double, 16>& EE_T_K) const;

  // Jacobian of `frame` with both rows in `frame` (bodyJacobian) or in the base frame (zeroJacobian).
  std::array<double, 42> bodyJacobian(Frame frame, const RobotState& robot_state) const;
  std::array<double, 42> bodyJacobian(Frame frame, const std::array<double, 7>& q,
                                      const std::array<double, 16>& F_T_EE, const std::array<double, 16>& EE_T_K) const;
  std::array<double, 42> zeroJacobian(Frame frame, const RobotState& robot_state) const;
  std::array<double, 42> zeroJacobian(Frame frame, const std::array<double, 7>& q,
                                      const std::array<double, 16>& F_T_EE, const std::array<double, 16>& EE_T_K) const;

  // Mass matrix M(q), column-major 7x7. The load is the total on the flange: end effector and
  // load together (RobotState::m_total, F_x_Ctotal, I_total).
  std::array<double, 49> mass(const RobotState& robot_state) const;
  std::array<double, 49> mass(const std::array<double, 7>& q, const std::array<double, 9>& I_total, double m_total,
                              const std::array<double, 3>& F_x_Ctotal) const;

  // Coriolis and centrifugal torques C(q, dq) dq [N m].
  std::array<double, 7> coriolis(const RobotState& robot_state) const;
  std::array<double, 7> coriolis(const std::array<double, 7>& q, const std::array<double, 7>& dq,
                                 const std::array<double, 9>& I_total, double m_total,
                                 const std::array<double, 3>& F_x_Ctotal) const;

  // Gravity torques g(q) that hold the arm still [N m].
  std::array<double, 7> gravity(const std::array<double, 7>& q, double m_total, const std::array<double, 3>& F_x_Ctotal,
                                const std::array<double, 3>& gravity_earth = {{0., 0., -9.81}}) const;
  std::array<double, 7> gravity(const RobotState& robot_state,
                                const std::array<double, 3>& gravity_earth = {{0., 0., -9.81}}) const;

 private:
  // What a call may change in the robot's model.
  struct Configuration {
    std::array<double, 16> F_T_EE{}, EE_T_K{};
    double m_total = 0.0;
    std::array<double, 3> F_x_Ctotal{};
    std::array<double, 9> I_total{};
    std::array<double, 3> gravity_earth{};
    bool operator==(const Configuration&) const = default;
  };

  // The robot's model in `configuration`, with forward kinematics at q done. The model is rebuilt
  // only when the configuration changes: a 1 kHz loop asking with one state does not rebuild it.
  const csp::Model& configured(const Configuration& configuration, const std::array<double, 7>& q) const;
  Configuration of_state(const RobotState& state) const;
  Configuration with_frames(const std::array<double, 16>& F_T_EE, const std::array<double, 16>& EE_T_K) const;
  Configuration with_load(double m_total, const std::array<double, 3>& F_x_Ctotal, const std::array<double, 9>& I_total) const;
  std::array<double, 42> jacobian(Frame frame, bool body, const Configuration& configuration,
                                  const std::array<double, 7>& q) const;

  csp::ModelParameters parameters_;   // the robot's parameters; end effector and load come per call
  mutable Configuration configuration_;
  mutable csp::Model model_;
  mutable csp::Data data_;
};

}  // namespace franka
