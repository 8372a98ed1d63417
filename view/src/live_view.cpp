#include "csp/view/live_view.hpp"

#include "csp/rt/csv_log.hpp"
#include "csp/view/recording.hpp"

namespace csp::view {

LiveView::LiveView(ViewServer& server, ViewRobot robot, double frames_per_second)
    : server_(server),
      model_(std::move(robot)),
      period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(1.0 / frames_per_second))),
      sender_(&LiveView::send_frames, this) {}

void LiveView::on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) {
  if (!wanted_.load(std::memory_order_relaxed)) return;
  std::unique_lock lock(mailbox_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;   // the sender is taking the last one: this frame waits for the next cycle
  mailbox_ = state;
  mailbox_command_received_ = cycle.command_received;
  mailbox_full_ = true;
  wanted_.store(false, std::memory_order_relaxed);
  lock.unlock();
  mailbox_ready_.notify_one();
}

void LiveView::send_frames() {
  auto next = std::chrono::steady_clock::now();
  std::unique_lock lock(mailbox_mutex_);
  for (;;) {
    if (mailbox_ready_.wait_until(lock, next, [&] { return stopping_; })) return;
    next += period_;
    if (server_.pages() == 0) continue;   // nobody watches: no frame to make
    wanted_.store(true, std::memory_order_relaxed);
    mailbox_ready_.wait(lock, [&] { return mailbox_full_ || stopping_; });
    if (!mailbox_full_) return;   // stopping
    const rt::RobotState state = mailbox_;
    const bool command_received = mailbox_command_received_;
    mailbox_full_ = false;
    lock.unlock();
    send_frame(state, command_received);
    lock.lock();
    next = std::max(next, std::chrono::steady_clock::now());   // a slow frame does not make the next ones late
  }
}

void LiveView::send_frame(const rt::RobotState& state, bool command_received) {
  last_sent_ms_ = state.time.toMSec();
  JointLog row;
  rt::append_state(row, state, command_received);
  nlohmann::json frame = model_.frame(row, 0);
  frame["type"] = "frame";
  nlohmann::json& values = frame["values"];
  for (const NumericColumn& column : plot_columns(row)) values[column.name] = column.values[0];
  if (server_.broadcast(frame.dump()) > 0) frames_sent_.fetch_add(1);
}

void LiveView::stop() {
  {
    const std::lock_guard lock(mailbox_mutex_);
    stopping_ = true;
  }
  mailbox_ready_.notify_all();
  if (sender_.joinable()) sender_.join();
}

void LiveView::finish(const rt::RobotState& last_state, const std::string& how) {
  stop();   // the sender has ended: last_sent_ms_ is this thread's now
  if (last_state.time.toMSec() != last_sent_ms_) send_frame(last_state, false);
  server_.broadcast(nlohmann::json{{"type", "end"}, {"text", how}, {"recording", server_.has_recording()}}.dump());
}

}  // namespace csp::view
