#include "view_option.hpp"

#include <chrono>
#include <cstdio>
#include <thread>

#include "cli_options.hpp"
#include "csp/view/inputs.hpp"

namespace csp::cli {

void ViewOption::add_to(CLI::App& command) {
  command.add_flag("--view", view, "Show the run live in a browser (csp view's page on 127.0.0.1)");
  command.add_option("--view-port", port, "The page's port with --view (0: a free port)")->capture_default_str()->check(CLI::Range(0, 65535));
}

LiveViewSession::LiveViewSession(const ViewOption& option, run::Run& run, const std::string& title) {
  const view::ViewRobot robot = view::view_robot(run.scenario());
  nlohmann::json description = view::ViewModel(robot).description();
  description["title"] = title;
  description["live"] = true;
  server_ = std::make_unique<view::ViewServer>("127.0.0.1", option.port, description);
  server_->on_notice([](const std::string& line) { std::fprintf(stderr, "csp %s: view: %s\n", command_name().c_str(), line.c_str()); });
  live_ = std::make_unique<view::LiveView>(*server_, robot);
  run.observe(*live_);
  std::printf("  view: %s\n", server_->url().c_str());
  std::fflush(stdout);
}

void LiveViewSession::wait_for_page(const std::atomic<bool>& stop) const {
  std::printf("  view: waiting for a page to open %s (Ctrl-C ends)\n", server_->url().c_str());
  std::fflush(stdout);
  while (server_->pages() == 0 && !stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

void LiveViewSession::finish(const run::Run& run, const std::string& how, const std::string& csv_log) {
  if (!csv_log.empty()) {
    view::ViewModel model(view::view_robot(run.scenario()));
    server_->set_recording(std::make_shared<view::Recording>(view::record(model, read_joint_log_csv(csv_log))));
  }
  live_->finish(run.emulator().state(), how);
}

void LiveViewSession::end(const run::Run& run, const run::RunResult& result) {
  const rt::RobotState& state = run.emulator().state();
  live_->finish(state, (result.stopped ? "stopped at t = " : "ended at t = ") + std::to_string(state.time.toSec()) + " s");
}

void LiveViewSession::serve_until_signal() const {
  std::printf("  view: %s stays served until Ctrl-C\n", server_->url().c_str());
  std::fflush(stdout);
  wait_for_signal();
}

void wait_for_signal() {
  const std::atomic<bool>& stop = stop_on_signals();
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
}

std::unique_ptr<LiveViewSession> start_live_view(const ViewOption& option, run::Run& run, const std::string& title) {
  if (!option.view) return nullptr;
  return std::make_unique<LiveViewSession>(option, run, title);
}

}  // namespace csp::cli
