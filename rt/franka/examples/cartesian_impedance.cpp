// Cartesian impedance: a spring-damper on the pose of the stiffness frame K holds the start pose
// (libfranka's cartesian_impedance_control example: 150 N/m, 10 N m/rad, critically damped),
// mapped to joint torques by the Jacobian's transpose, plus Coriolis. Runs 8 s, through the
// default scenario's push on the hand at 6 s, and prints the largest position error.
//
// usage: csp_example_cartesian_impedance <robot-hostname or scenario.yaml>
// (a hostname or IP address runs on $CSP_SCENARIO or configs/scenarios/libfranka_panda.yaml)
#include <algorithm>
#include <cmath>
#include <iostream>

#include <Eigen/Dense>

#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname or scenario.yaml>" << std::endl;
    return -1;
  }
  const std::string scenario = argv[1];
  try {
    franka::Robot robot(scenario);
    franka::Model model = robot.loadModel();
    const double translational_stiffness = 150.0, rotational_stiffness = 10.0;
    Eigen::Matrix<double, 6, 6> stiffness = Eigen::Matrix<double, 6, 6>::Zero(), damping;
    stiffness.topLeftCorner<3, 3>() = translational_stiffness * Eigen::Matrix3d::Identity();
    stiffness.bottomRightCorner<3, 3>() = rotational_stiffness * Eigen::Matrix3d::Identity();
    damping = 2.0 * stiffness.cwiseSqrt();

    const franka::RobotState start = robot.readOnce();
    const Eigen::Affine3d start_pose(Eigen::Matrix4d::Map(model.pose(franka::Frame::kStiffness, start).data()));
    const Eigen::Vector3d position_d = start_pose.translation();
    const Eigen::Quaterniond orientation_d(start_pose.rotation());

    double time = 0.0, largest_error = 0.0;
    robot.control([&](const franka::RobotState& state, franka::Duration period) -> franka::Torques {
      time += period.toSec();
      const std::array<double, 42> jacobian_array = model.zeroJacobian(franka::Frame::kStiffness, state);
      const std::array<double, 7> coriolis_array = model.coriolis(state);
      const Eigen::Map<const Eigen::Matrix<double, 6, 7>> jacobian(jacobian_array.data());
      const Eigen::Map<const Eigen::Matrix<double, 7, 1>> dq(state.dq.data()), coriolis(coriolis_array.data());
      const Eigen::Affine3d pose(Eigen::Matrix4d::Map(model.pose(franka::Frame::kStiffness, state).data()));

      Eigen::Matrix<double, 6, 1> error;
      error.head<3>() = pose.translation() - position_d;
      Eigen::Quaterniond orientation(pose.rotation());
      if (orientation_d.coeffs().dot(orientation.coeffs()) < 0.0) orientation.coeffs() = -orientation.coeffs();
      // Orientation error as the vector part of the error quaternion, in the base frame.
      const Eigen::Quaterniond difference(orientation.inverse() * orientation_d);
      error.tail<3>() = -pose.rotation() * Eigen::Vector3d(difference.x(), difference.y(), difference.z());
      largest_error = std::max(largest_error, error.head<3>().norm());

      const Eigen::Matrix<double, 7, 1> tau =
          jacobian.transpose() * (-stiffness * error - damping * (jacobian * dq)) + coriolis;
      std::array<double, 7> tau_array{};
      Eigen::Matrix<double, 7, 1>::Map(tau_array.data()) = tau;
      return time >= 8.0 ? franka::MotionFinished(franka::Torques(tau_array)) : franka::Torques(tau_array);
    });
    std::cout << "largest position error of K over 8 s: " << largest_error * 1000.0 << " mm\n";
  } catch (const franka::Exception& e) {
    std::cerr << e.what() << '\n';
    return 1;
  }
  return 0;
}
