// A run shown live (csp emulate/serve/fci --view, csp can serve --view): an observer of the run
// that hands a state to its own thread when the display wants one, and that thread makes the
// frame (forward kinematics, clearance, JSON) and sends it to every page at the display's rate.
//
// It never slows the 1 kHz loop: on a cycle the display does not want, on_cycle reads one atomic
// flag; on one it wants (30 times a second), it copies the state under a mutex the sender holds
// only to swap it out, and skips the frame rather than wait if the sender has it. Nothing on the
// loop's side allocates. (bench/bench_view.cpp measures the cycle with and without a page attached.)
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "csp/run/run.hpp"
#include "csp/view/server.hpp"
#include "csp/view/view_model.hpp"

namespace csp::view {

class LiveView : public run::Observer {
 public:
  // Frames to the pages of `server` at `frames_per_second` of wall time (at most).
  LiveView(ViewServer& server, ViewRobot robot, double frames_per_second = 30.0);
  ~LiveView() override { stop(); }
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override;

  // The run is over: the sender stops, the pages get the robot's last state (unless it was the last
  // frame sent) and then
  // {"type": "end", "text": how, "recording": whether the server has the whole run to load}.
  void finish(const rt::RobotState& last_state, const std::string& how);

  uint64_t frames_sent() const { return frames_sent_.load(); }   // frames that reached a page at least

 private:
  void send_frames();
  void stop();
  void send_frame(const rt::RobotState& state, bool command_received);

  ViewServer& server_;
  ViewModel model_;
  std::chrono::steady_clock::duration period_;

  std::atomic<bool> wanted_{false};   // the sender waits for a state
  std::mutex mailbox_mutex_;
  std::condition_variable mailbox_ready_;
  rt::RobotState mailbox_{};
  bool mailbox_command_received_ = false;
  bool mailbox_full_ = false;
  bool stopping_ = false;

  std::atomic<uint64_t> frames_sent_{0};
  uint64_t last_sent_ms_ = UINT64_MAX;   // robot time of the last frame made (the sender's, then finish's)
  std::thread sender_;
};

}  // namespace csp::view
