// Joint impedance control of a Cartesian circle: the robot's motion generator turns a circular
// Cartesian pose trajectory (5 cm radius, in the y-z plane) into joint targets q_d with its inverse
// kinematics, and the program tracks them with its own joint impedance law plus the Coriolis
// torque from franka::Model. The torque is rate-limited with franka::limitRate, and a separate
// thread prints commanded against measured torques at 10 Hz so that printing never blocks the
// 1 kHz loop.
//
// Warning: the robot moves; make sure there is enough space around it.
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <mutex>
#include <thread>

#include <franka/duration.h>
#include <franka/exception.h>
#include <franka/model.h>
#include <franka/rate_limiting.h>
#include <franka/robot.h>

#include "examples_common.h"

namespace {
template <class T, size_t N>
std::ostream& operator<<(std::ostream& stream, const std::array<T, N>& array) {
  stream << "[";
  for (size_t i = 0; i < N; ++i) {
    stream << (i == 0 ? "" : ",") << array[i];
  }
  return stream << "]";
}

// What the control loop hands to the print thread.
struct PrintData {
  std::mutex mutex;
  bool has_data = false;
  std::array<double, 7> tau_d{};    // commanded torque, without gravity [Nm]
  std::array<double, 7> gravity{};  // [Nm]
  std::array<double, 7> tau_J{};    // measured link-side torque [Nm]
};

void printTorques(PrintData& data) {
  std::array<double, 7> tau_commanded{};
  std::array<double, 7> tau_error{};
  double squares = 0.0;
  for (size_t i = 0; i < 7; ++i) {
    // The robot adds gravity compensation to the user's torque; tau_J measures the sum.
    tau_commanded[i] = data.tau_d[i] + data.gravity[i];
    tau_error[i] = tau_commanded[i] - data.tau_J[i];
    squares += tau_error[i] * tau_error[i];
  }
  std::cout << "tau_error [Nm]: " << tau_error << std::endl
            << "tau_commanded [Nm]: " << tau_commanded << std::endl
            << "tau_measured [Nm]: " << data.tau_J << std::endl
            << "root mean square of tau_error [Nm]: " << std::sqrt(squares / 7.0) << std::endl
            << "-----------------------" << std::endl;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "Usage: " << argv[0] << " <robot-hostname>" << std::endl;
    return -1;
  }

  constexpr double kRadius = 0.05;           // [m]
  constexpr double kSpeedMax = 0.25;         // along the circle [m/s]
  constexpr double kAccelerationTime = 2.0;  // to reach kSpeedMax and to stop again [s]
  constexpr double kRunTime = 20.0;          // [s]
  constexpr double kPrintRate = 10.0;        // [Hz]

  PrintData print_data;
  std::atomic_bool running{true};
  std::thread print_thread([&print_data, &running]() {
    while (running) {
      std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / kPrintRate));
      // try_lock: the printer waits for the control loop, never the other way round.
      if (print_data.mutex.try_lock()) {
        if (print_data.has_data) {
          printTorques(print_data);
          print_data.has_data = false;
        }
        print_data.mutex.unlock();
      }
    }
  });

  try {
    franka::Robot robot(argv[1]);
    setDefaultBehavior(robot);
    moveToStartPose(robot);

    setMotionCollisionBehavior(robot);
    franka::Model model = robot.loadModel();

    std::array<double, 16> pose_initial{};
    double time = 0.0;
    double speed = 0.0;  // along the circle [m/s]
    double angle = 0.0;  // on the circle [rad]
    auto circle = [&](const franka::RobotState& robot_state,
                      franka::Duration period) -> franka::CartesianPose {
      time += period.toSec();
      if (time == 0.0) {
        pose_initial = robot_state.O_T_EE_c;
      }

      // Constant acceleration up to kSpeedMax, then the same deceleration after kRunTime.
      const double speed_step = period.toSec() * kSpeedMax / kAccelerationTime;
      speed += time < kRunTime ? speed_step : -speed_step;
      speed = std::fmin(std::fmax(speed, 0.0), kSpeedMax);
      angle = std::fmod(angle + period.toSec() * speed / kRadius, 2.0 * M_PI);

      franka::CartesianPose pose(pose_initial);
      pose.O_T_EE[13] += kRadius * (1.0 - std::cos(angle));
      pose.O_T_EE[14] += kRadius * std::sin(angle);
      if (time >= kRunTime + kAccelerationTime) {
        running = false;
        return franka::MotionFinished(pose);
      }
      return pose;
    };

    const std::array<double, 7> stiffness{{600.0, 600.0, 600.0, 600.0, 250.0, 150.0, 50.0}};
    const std::array<double, 7> damping{{50.0, 50.0, 50.0, 50.0, 30.0, 25.0, 15.0}};
    std::function<franka::Torques(const franka::RobotState&, franka::Duration)> impedance =
        [&](const franka::RobotState& state, franka::Duration /*period*/) -> franka::Torques {
      // The robot's inverse kinematics answers the circle's pose in q_d, one cycle later.
      const std::array<double, 7> coriolis = model.coriolis(state);
      std::array<double, 7> tau_d{};
      for (size_t i = 0; i < 7; ++i) {
        tau_d[i] =
            stiffness[i] * (state.q_d[i] - state.q[i]) - damping[i] * state.dq[i] + coriolis[i];
      }
      // Robot::control rate-limits the torque anyway (limit_rate defaults to true); limiting it
      // here as well lets the print thread show what the robot is really sent.
      tau_d = franka::limitRate(franka::kMaxTorqueRate, tau_d, state.tau_J_d);

      if (print_data.mutex.try_lock()) {
        print_data.has_data = true;
        print_data.tau_d = tau_d;
        print_data.gravity = model.gravity(state);
        print_data.tau_J = state.tau_J;
        print_data.mutex.unlock();
      }
      return tau_d;
    };

    robot.control(impedance, circle);
  } catch (const franka::Exception& e) {
    running = false;
    print_thread.join();
    std::cerr << e.what() << std::endl;
    return -1;
  }

  running = false;
  print_thread.join();
  std::cout << "Finished." << std::endl;
  return 0;
}
