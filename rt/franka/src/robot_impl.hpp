// franka::Robot's implementation: the emulated robot, its motions (one csp::rt::MotionSession each,
// for control() and for the external control loop alike), the robot time that passes between the
// program's calls, and the log a ControlException carries.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"
#include "franka/exception.h"
#include "franka/robot.h"

namespace franka {

class Robot::Impl {
 public:
  // The robot keeps cycling while the program is outside a call; on the next call the idle cycles
  // are run, at most this many (10 s: a program waiting for Enter does not wait for a day of
  // emulation afterwards).
  static constexpr int64_t kMaxIdleCycles = 10'000;

  Impl(const csp::rt::Scenario& scenario, RealtimeConfig realtime_config, std::size_t log_size);

  // Runs the cycles that passed since the program's last call (idle_time_runs), at most kMaxIdleCycles.
  void catch_up_idle_time();
  // Ends a call: robot time runs on from now.
  void mark_idle();

  // Starts a motion (catching up the idle time first). ControlException when the robot is in
  // Reflex, InvalidOperationException while another motion runs, RealtimeException as control().
  csp::rt::MotionSession& start_motion(csp::rt::ControlMode mode, std::optional<csp::rt::ControllerMode> controller);
  // Ends the session of a motion that is over: nothing after a finished motion; ControlException
  // after a reflex ("motion aborted by reflex!" with the errors) or a stop ("Move command preempted!").
  void end_motion();
  // The program failed on the state read last (a callback threw, or sent NaN): the robot's command
  // intake ends the motion in a reflex with `reason`.
  void fail_motion(const std::string& reason);
  // The session ends with the robot holding its last command (Robot::stop, a handle destroyed
  // before its motion finished).
  void cancel_motion();
  // The next state outside motions.
  RobotState read_once();

  csp::rt::Emulator emulator;
  std::string robot_name;        // the robot file's name (panda, fr3): getRobotModel's prefix
  csp::rt::LoopOptions loop_options;
  csp::rt::TimingReport last_timing;
  csp::rt::CycleObserver user_observer;
  bool idle_time_runs = true;   // off: robot time moves only inside calls (bit-reproducible tests)
  std::mutex control_mutex;     // held by control(), read() and an external control loop's handle
  std::atomic<bool> stop_requested{false};
  std::optional<csp::rt::MotionSession> session;
  uint32_t motion_id = 0;       // of the session; a handle of an older motion finds it changed
  std::array<bool, 6> guiding_mode{{true, true, true, true, true, true}};
  bool guiding_elbow = false;

 private:
  void record(const RobotState& state, const csp::rt::CycleInfo& cycle);
  std::vector<Record> recent_log() const;

  std::vector<Record> log_;   // ring buffer of the last cycles
  std::size_t log_next_ = 0, log_count_ = 0;
  int64_t idle_since_ns_ = 0;
  std::optional<csp::rt::ControlMode> mode_;   // of the running motion, for the log
};

}  // namespace franka
