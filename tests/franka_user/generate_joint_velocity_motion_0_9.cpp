// libfranka 0.9's rate limiting, done by the program itself: joint 4 is commanded a velocity step
// (0.5 rad/s for 1 s, then 0), far beyond what the robot accepts in one millisecond. Each command
// goes through 0.9's franka::limitRate(max_velocity, max_acceleration, max_jerk, ...) with its
// Panda limits (kMaxJointVelocity, kMaxJointAcceleration, kMaxJointJerk) before Robot::control,
// which runs with its own rate limiter and low-pass filter off. With "raw" as the second argument
// the step goes to the robot unlimited, which the robot refuses with a reflex.
//
// Builds against libfranka 0.9.x; with CSP, compile with CSP_FRANKA_API_VERSION=900.
//
// Warning: the robot moves; make sure there is enough space around it.
#include <array>
#include <iostream>
#include <string>

#include <franka/exception.h>
#include <franka/lowpass_filter.h>
#include <franka/rate_limiting.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  const bool raw = argc == 3 && std::string(argv[2]) == "raw";
  if (argc != 2 && !raw) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname> [raw]" << std::endl;
    return -1;
  }

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);
    setMotionCollisionBehavior(robot);

    constexpr size_t kJoint = 3;
    constexpr double kStepVelocity = 0.5;  // [rad/s]
    double time = 0.0;
    robot.control(
        [&](const franka::RobotState& state, franka::Duration period) -> franka::JointVelocities {
          time += period.toSec();

          std::array<double, 7> dq_command{};
          dq_command[kJoint] = time < 1.0 ? kStepVelocity : 0.0;
          if (!raw) {
            // From the last desired velocity and acceleration (dq_d, ddq_d), as 0.9 does inside
            // control.
            dq_command =
                franka::limitRate(franka::kMaxJointVelocity, franka::kMaxJointAcceleration,
                                  franka::kMaxJointJerk, dq_command, state.dq_d, state.ddq_d);
          }

          franka::JointVelocities output(dq_command);
          if (time >= 2.0) {
            std::cout << std::endl << "Finished motion, shutting down example" << std::endl;
            return franka::MotionFinished(output);
          }
          return output;
        },
        franka::ControllerMode::kJointImpedance, false, franka::kMaxCutoffFrequency);
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }
  return 0;
}
