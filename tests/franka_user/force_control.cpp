// PI force control: the end effector presses down along the base's z axis with the weight of a
// target mass of 1 kg, ramped in smoothly. The force is measured through the joint torque sensors
// (tau_J minus gravity minus the sensors' offset at the start). Without a surface under the
// robot, the arm moves down and the program stops once it is 1 cm away from where it started.
//
// Warning: mount no end effector, and put the robot's last joint in contact with a horizontal
// rigid surface before starting. Collision thresholds are set high.
#include <array>
#include <iostream>
#include <stdexcept>

#include <Eigen/Core>

#include <franka/duration.h>
#include <franka/exception.h>
#include <franka/model.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  constexpr double kTargetMass = 1.0;    // [kg]
  constexpr double kGravity = 9.81;      // [m/s^2]
  constexpr double kP = 1.0;             // proportional gain on the torque error
  constexpr double kI = 2.0;             // integral gain [1/s]
  constexpr double kFilterGain = 0.001;  // per cycle: the mass ramps in over about a second
  constexpr double kMaxDistance = 0.01;  // [m] from the start before the program gives up

  using Vector7d = Eigen::Matrix<double, 7, 1>;

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    franka::Model model = robot.loadModel();

    robot.setCollisionBehavior({{100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0}},
                               {{100.0, 100.0, 100.0, 100.0, 100.0, 100.0}});

    // At rest the sensors read gravity plus their offset: remember the offset.
    const franka::RobotState initial_state = robot.readOnce();
    const std::array<double, 7> gravity_array = model.gravity(initial_state);
    const Eigen::Map<const Vector7d> gravity(gravity_array.data());
    const Vector7d tau_offset = Vector7d(initial_state.tau_J.data()) - gravity;

    Vector7d tau_error_integral = Vector7d::Zero();
    double mass = 0.0;  // [kg], filtered towards kTargetMass
    Eigen::Vector3d position_initial = Eigen::Vector3d::Zero();
    double time = 0.0;
    auto position = [](const franka::RobotState& state) {
      return Eigen::Vector3d(state.O_T_EE[12], state.O_T_EE[13], state.O_T_EE[14]);
    };

    auto force_control = [&](const franka::RobotState& state,
                             franka::Duration period) -> franka::Torques {
      time += period.toSec();
      if (time == 0.0) {
        position_initial = position(state);
      }
      if ((position(state) - position_initial).norm() > kMaxDistance) {
        throw std::runtime_error("Aborting; too far away from starting pose!");
      }

      const std::array<double, 42> jacobian_array =
          model.zeroJacobian(franka::Frame::kEndEffector, state);
      const Eigen::Map<const Eigen::Matrix<double, 6, 7>> jacobian(jacobian_array.data());
      const Eigen::Map<const Vector7d> tau_measured(state.tau_J.data());

      Eigen::Matrix<double, 6, 1> wrench_d = Eigen::Matrix<double, 6, 1>::Zero();
      wrench_d(2) = -mass * kGravity;
      const Vector7d tau_d = jacobian.transpose() * wrench_d;
      const Vector7d tau_ext = tau_measured - gravity - tau_offset;
      tau_error_integral += period.toSec() * (tau_d - tau_ext);
      // Feed-forward plus PI on the torque error.
      const Vector7d tau_command = tau_d + kP * (tau_d - tau_ext) + kI * tau_error_integral;

      mass += kFilterGain * (kTargetMass - mass);

      std::array<double, 7> tau_array{};
      Eigen::Map<Vector7d>(tau_array.data()) = tau_command;
      return franka::Torques(tau_array);
    };

    std::cout << "WARNING: Make sure that no end effector is mounted and that the robot's last "
                 "joint is in contact with a horizontal rigid surface before starting. Keep in "
                 "mind that collision thresholds are set to high values."
              << std::endl
              << "Press Enter to continue..." << std::endl;
    std::cin.ignore();
    robot.control(force_control);
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  } catch (const std::runtime_error& e) {  // the controller's own stop
    std::cout << e.what() << std::endl;
  }
  return 0;
}
