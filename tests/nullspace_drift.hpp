// libfranka's cartesian_impedance_control example (0.15.0) as it runs on the robot, written against
// csp::rt::Emulator directly: the example's stiffness (150 N/m, 10 N m/rad) and critical damping,
// the EE-frame Jacobian, pose and Coriolis of the robot's own model, libfranka's 100 Hz low-pass of
// the commanded torque against tau_J_d, the collision thresholds the example sets (100), torque
// mode, lockstep. It records how far the arm drifts in the impedance's null space (the self-motion
// the 6-D Cartesian spring cannot see) and whether a reflex ends the run. docs/emulator.md, section
// "Null-space drift and static friction", reports what it measures.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <vector>

#include "csp/rt/emulator.hpp"

namespace csp::test {

struct DriftSample {
  double t = 0.0;
  Vector7 q_change = Vector7::Zero();   // q(t) - q(0) [rad]
  double self_motion = 0.0;             // n^T (q(t) - q(0)), n the unit null-space direction of J(q0) [rad]
  double position_error = 0.0;          // |p_EE(t) - p_EE(0)| [m]
};

struct DriftRun {
  std::vector<DriftSample> samples;   // every `sample_period` and at the end
  std::string reflex;                 // empty: ran to the end
  double end_time = 0.0;              // [s] the run's end (the reflex's time if one came)
  Vector7 largest_change = Vector7::Zero();   // max |q - q0| per joint over the run [rad]
};

// The unit direction n with J n = 0 (the Panda's one-dimensional self-motion): the signed 6x6
// minors of J (n_i = (-1)^i det J without column i) span its kernel. Sign: n[3] (the elbow) > 0.
inline Vector7 null_space_direction(const Matrix6x7& jacobian) {
  Vector7 n;
  for (int i = 0; i < 7; ++i) {
    Matrix6 minor;
    for (int c = 0, k = 0; c < 7; ++c)
      if (c != i) minor.col(k++) = jacobian.col(c);
    n[i] = (i % 2 == 0 ? 1.0 : -1.0) * minor.determinant();
  }
  n.normalize();
  return n[3] < 0.0 ? Vector7(-n) : n;
}

// Runs the example on `settings` for `duration` seconds.
inline DriftRun run_cartesian_impedance(const rt::EmulatorSettings& settings, double duration, double sample_period) {
  rt::EmulatorSettings s = settings;
  // setCollisionBehavior of the example: 100 N m / 100 N for contact and collision, both phases.
  s.collision.lower_torque_acceleration = s.collision.upper_torque_acceleration = Vector7::Constant(100.0);
  s.collision.lower_torque_nominal = s.collision.upper_torque_nominal = Vector7::Constant(100.0);
  s.collision.lower_force_acceleration = s.collision.upper_force_acceleration = Vector6::Constant(100.0);
  s.collision.lower_force_nominal = s.collision.upper_force_nominal = Vector6::Constant(100.0);
  rt::Emulator robot(s);
  const Model& model = robot.internal_model();   // franka::Model: the robot's own model
  Data data;

  const double translational_stiffness = 150.0, rotational_stiffness = 10.0;
  Matrix6 stiffness = Matrix6::Zero(), damping = Matrix6::Zero();
  stiffness.topLeftCorner<3, 3>() = translational_stiffness * Matrix3::Identity();
  stiffness.bottomRightCorner<3, 3>() = rotational_stiffness * Matrix3::Identity();
  damping.topLeftCorner<3, 3>() = 2.0 * std::sqrt(translational_stiffness) * Matrix3::Identity();
  damping.bottomRightCorner<3, 3>() = 2.0 * std::sqrt(rotational_stiffness) * Matrix3::Identity();

  const Vector7 q0 = Eigen::Map<const Vector7>(robot.state().q.data());
  forward_kinematics(model, data, q0);
  const Vector3 position_d = data.O_T_EE.translation;
  const Eigen::Quaterniond orientation_d(data.O_T_EE.rotation);
  Matrix6x7 jacobian;
  zero_jacobian(data, Frame::kEndEffector, jacobian);
  const Vector7 n = null_space_direction(jacobian);

  // libfranka's lowpassFilter(kDeltaT, tau_d, tau_J_d, 100 Hz) (control_loop.cpp).
  const double cutoff_hz = 100.0, a = 2.0 * M_PI * rt::kDeltaT * cutoff_hz;
  const double filter_gain = a / (a + 1.0);

  DriftRun run;
  const auto record = [&](double t, const Vector7& q) {
    forward_kinematics(model, data, q);
    run.samples.push_back({t, q - q0, n.dot(q - q0), (data.O_T_EE.translation - position_d).norm()});
  };
  record(0.0, q0);
  robot.start_motion(rt::ControlMode::kTorque);
  const long cycles = std::lround(duration / rt::kDeltaT);
  const long sample_every = std::max(1L, std::lround(sample_period / rt::kDeltaT));
  rt::Command command;
  for (long k = 1; k <= cycles && robot.in_motion(); ++k) {
    const rt::RobotState& state = robot.state();
    const Vector7 q = Eigen::Map<const Vector7>(state.q.data()), dq = Eigen::Map<const Vector7>(state.dq.data());
    const Vector7 tau_J_d = Eigen::Map<const Vector7>(state.tau_J_d.data());
    forward_kinematics(model, data, q);
    zero_jacobian(data, Frame::kEndEffector, jacobian);
    Vector7 coriolis;
    coriolis_torque(model, data, q, dq, coriolis);
    Eigen::Quaterniond orientation(data.O_T_EE.rotation);
    Vector6 error;
    error.head<3>() = data.O_T_EE.translation - position_d;
    if (orientation_d.coeffs().dot(orientation.coeffs()) < 0.0) orientation.coeffs() = -orientation.coeffs();
    const Eigen::Quaterniond difference(orientation.inverse() * orientation_d);
    error.tail<3>() = -data.O_T_EE.rotation * Vector3(difference.x(), difference.y(), difference.z());
    const Vector7 tau_d = jacobian.transpose() * (-stiffness * error - damping * (jacobian * dq)) + coriolis;
    command.values = tau_J_d + filter_gain * (tau_d - tau_J_d);
    robot.step(&command);

    const Vector7 q_now = Eigen::Map<const Vector7>(robot.state().q.data());
    run.largest_change = run.largest_change.cwiseMax((q_now - q0).cwiseAbs());
    run.end_time = static_cast<double>(k) * rt::kDeltaT;
    if (k % sample_every == 0 || k == cycles || !robot.in_motion()) record(run.end_time, q_now);
  }
  run.reflex = robot.reflex_reason();
  return run;
}

}  // namespace csp::test
