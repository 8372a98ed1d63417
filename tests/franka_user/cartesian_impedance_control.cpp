// Cartesian impedance control without inertia shaping: the torque controller renders a critically
// damped spring at the end effector, with the initial pose as its equilibrium. Push the robot and
// feel it return. Ends after [run-time] seconds (default: runs until an error or the user stop).
//
// Warning: collision thresholds are set high; keep the user stop at hand.
#include <array>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include <franka/duration.h>
#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  double run_time = std::numeric_limits<double>::infinity();  // [s]
  bool arguments_valid = argc == 2 || argc == 3;
  if (argc == 3) {
    try {
      run_time = std::stod(argv[2]);
      arguments_valid = run_time > 0.0;
    } catch (const std::exception&) {
      arguments_valid = false;
    }
  }
  if (!arguments_valid) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname> [run-time]" << std::endl
              << "run-time: seconds of control, a positive number (default: no end)." << std::endl;
    return -1;
  }

  // Spring [N/m, Nm/rad] and damping for a damping ratio of 1 (unit mass): 2 sqrt(k).
  constexpr double kTranslationalStiffness = 150.0;
  constexpr double kRotationalStiffness = 10.0;
  Eigen::Matrix<double, 6, 6> stiffness = Eigen::Matrix<double, 6, 6>::Zero();
  stiffness.topLeftCorner<3, 3>().diagonal().setConstant(kTranslationalStiffness);
  stiffness.bottomRightCorner<3, 3>().diagonal().setConstant(kRotationalStiffness);
  const Eigen::Matrix<double, 6, 6> damping = 2.0 * stiffness.cwiseSqrt();

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    franka::Model model = robot.loadModel();

    const franka::RobotState initial_state = robot.readOnce();
    const Eigen::Affine3d initial_transform(Eigen::Matrix4d::Map(initial_state.O_T_EE.data()));
    const Eigen::Vector3d position_d(initial_transform.translation());
    const Eigen::Quaterniond orientation_d(initial_transform.rotation());

    // Contact and collision torque and force thresholds, high so that pushing is allowed.
    robot.setCollisionBehavior({{100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0}});

    double time = 0.0;
    std::function<franka::Torques(const franka::RobotState&, franka::Duration)> impedance =
        [&](const franka::RobotState& state, franka::Duration period) -> franka::Torques {
      time += period.toSec();

      const std::array<double, 7> coriolis_array = model.coriolis(state);
      const std::array<double, 42> jacobian_array =
          model.zeroJacobian(franka::Frame::kEndEffector, state);
      const Eigen::Map<const Eigen::Matrix<double, 7, 1>> coriolis(coriolis_array.data());
      const Eigen::Map<const Eigen::Matrix<double, 6, 7>> jacobian(jacobian_array.data());
      const Eigen::Map<const Eigen::Matrix<double, 7, 1>> dq(state.dq.data());
      const Eigen::Affine3d transform(Eigen::Matrix4d::Map(state.O_T_EE.data()));
      Eigen::Quaterniond orientation(transform.rotation());

      // Pose error: position difference, and the vector part of the rotation from the current
      // to the desired orientation, expressed in the base frame.
      Eigen::Matrix<double, 6, 1> error;
      error.head<3>() = transform.translation() - position_d;
      if (orientation_d.coeffs().dot(orientation.coeffs()) < 0.0) {
        orientation.coeffs() = -orientation.coeffs();  // the shorter way round
      }
      const Eigen::Quaterniond rotation_error(orientation.inverse() * orientation_d);
      error.tail<3>() = -transform.rotation() * rotation_error.vec();

      // Spring and damper at the end effector, mapped to joint torques; the robot adds gravity.
      const Eigen::Matrix<double, 7, 1> tau_d =
          jacobian.transpose() * (-stiffness * error - damping * (jacobian * dq)) + coriolis;

      std::array<double, 7> tau_d_array{};
      Eigen::Map<Eigen::Matrix<double, 7, 1>>(tau_d_array.data()) = tau_d;
      franka::Torques output(tau_d_array);
      if (time >= run_time) {
        return franka::MotionFinished(output);
      }
      return output;
    };

    std::cout << "WARNING: Collision thresholds are set to high values. "
              << "Make sure you have the user stop at hand!" << std::endl
              << "After starting try to push the robot and see how it reacts." << std::endl
              << "Press Enter to continue..." << std::endl;
    std::cin.ignore();
    robot.control(impedance);
    std::cout << "Finished." << std::endl;
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
