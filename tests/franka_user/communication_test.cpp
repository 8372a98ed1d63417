// Measures how reliably commands reach the robot: for 10 s the program sends zero torques through
// the external control loop (startTorqueControl, readOnce, writeOnce) and reports the robot's
// control_command_success_rate and the robot states the loop missed.
//
// Warning: the robot moves to its start pose first; make sure there is enough space in front of it.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <thread>

#include <franka/active_control.h>
#include <franka/active_torque_control.h>
#include <franka/duration.h>
#include <franka/exception.h>
#include <franka/robot.h>

#include "examples_common.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  uint64_t samples = 0;     // loop cycles after the first
  uint64_t robot_time = 0;  // [ms] of robot time since the first cycle
  double success_sum = 0.0;
  double success_min = 1.0;
  double success_max = 0.0;
  std::cout.precision(2);
  std::cout << std::fixed;

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);
    std::cout << std::endl << "Starting communication test." << std::endl;

    setMotionCollisionBehavior(robot);
    // With the end effector configured correctly, zero torques (on top of the robot's own gravity
    // compensation) leave the arm where it is.
    franka::Torques zero_torques{{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}};
    auto active_control = robot.startTorqueControl();

    while (!zero_torques.motion_finished) {
      const auto [robot_state, period] = active_control->readOnce();
      robot_time += period.toMSec();
      if (robot_time > 0) {
        ++samples;
        const double rate = robot_state.control_command_success_rate;
        success_sum += rate;
        success_min = std::min(success_min, rate);
        success_max = std::max(success_max, rate);
        if (samples % 100 == 0) {
          std::cout << "#" << samples << " Current success rate: " << rate << std::endl;
        }
        // Stands for the work of a real controller between reading and writing.
        std::this_thread::sleep_for(std::chrono::microseconds(100));
        if (robot_time >= 10000) {
          std::cout << std::endl << "Finished test, shutting down example" << std::endl;
          zero_torques.motion_finished = true;
        }
      }
      active_control->writeOnce(zero_torques);
    }
  } catch (const franka::Exception& e) {
    std::cout << e.what() << std::endl;
    return -1;
  }

  const double success_mean = samples > 0 ? success_sum / static_cast<double>(samples) : 0.0;
  std::cout << std::endl << "#######################################################" << std::endl;
  // One robot state per millisecond: each millisecond without a loop cycle is a lost state.
  const uint64_t lost_states = robot_time - samples;
  if (lost_states > 0) {
    std::cout << "The control loop did not get executed " << lost_states << " times in the"
              << std::endl
              << "last " << robot_time << " milliseconds! (lost " << lost_states << " robot states)"
              << std::endl
              << std::endl;
  }
  std::cout << "Control command success rate of " << samples << " samples: " << std::endl
            << "Max: " << success_max << std::endl
            << "Avg: " << success_mean << std::endl
            << "Min: " << success_min << std::endl;
  if (success_mean < 0.90) {
    std::cout << std::endl
              << "WARNING: THIS SETUP IS PROBABLY NOT SUFFICIENT FOR FCI!" << std::endl
              << "PLEASE TRY OUT A DIFFERENT PC / NIC" << std::endl;
  } else if (success_mean < 0.95) {
    std::cout << std::endl
              << "WARNING: MANY PACKETS GOT LOST!" << std::endl
              << "PLEASE INSPECT YOUR SETUP AND FOLLOW ADVICE ON" << std::endl
              << "https://frankaemika.github.io/docs/troubleshooting.html" << std::endl;
  }
  std::cout << "#######################################################" << std::endl;
  return 0;
}
