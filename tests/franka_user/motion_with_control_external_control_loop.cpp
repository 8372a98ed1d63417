// The motion of motion_with_control with the external control loop of libfranka 0.15: a joint
// velocity control session in ControllerMode::kExternalController, where each writeOnce carries
// the motion generator's velocities and the program's torques together.
//
// Warning: the robot moves; make sure there is enough space in front of it.
#include <array>
#include <iostream>

#include <franka/active_control.h>
#include <franka/active_motion_generator.h>
#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  // NOLINTNEXTLINE(readability-identifier-naming)
  const std::array<double, 7> K_P{{200.0, 200.0, 200.0, 200.0, 200.0, 200.0, 200.0}};
  // NOLINTNEXTLINE(readability-identifier-naming)
  const std::array<double, 7> K_D{{10.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0}};

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);

    setMotionCollisionBehavior(robot);
    JointPdController controller(K_P, K_D);
    JointVelocityRamp motion(3, 1.0);
    auto active_control = robot.startJointVelocityControl(
        research_interface::robot::Move::ControllerMode::kExternalController);
    bool motion_finished = false;
    while (!motion_finished) {
      const auto [robot_state, period] = active_control->readOnce();
      const franka::JointVelocities velocities = motion(robot_state, period);
      const franka::Torques torques = controller(robot_state, period);
      motion_finished = velocities.motion_finished;
      active_control->writeOnce(velocities, torques);
    }
  } catch (const franka::ControlException& e) {
    std::cout << e.what() << std::endl;
    writeLogToFile(e.log);
    return -1;
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
