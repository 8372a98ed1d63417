// `--view` on the commands that run the robot (csp emulate, serve, can serve, fci): the run shown
// live in a browser (csp view's page, docs/view.md), served on 127.0.0.1.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "csp/run/run.hpp"
#include "csp/view/live_view.hpp"

namespace csp::cli {

struct ViewOption {
  bool view = false;
  int port = 8080;   // 0: a free port

  void add_to(CLI::App& command);
};

// The page's server and the run's live observer, when --view was given (else nothing happens).
class LiveViewSession {
 public:
  // Serves the page for `run`'s robot and scene and prints its address; the observer is added to
  // `run`. Throws std::runtime_error when the port cannot be served.
  LiveViewSession(const ViewOption& option, run::Run& run, const std::string& title);
  // A bus's run is over (csp serve, can serve, fci): the pages are told how, at which time. The
  // process ends next: the page keeps what it was sent.
  void end(const run::Run& run, const run::RunResult& result);
  // Until a page is connected or `stop` is set (a signal): csp emulate starts its run for someone.
  void wait_for_page(const std::atomic<bool>& stop) const;
  // The run is over (`how`): the pages are told; with the run's CSV log (may be empty), the page
  // gets the whole run to scrub.
  void finish(const run::Run& run, const std::string& how, const std::string& csv_log);
  // The page stays served after the run, until Ctrl-C.
  void serve_until_signal() const;

 private:
  std::unique_ptr<view::ViewServer> server_;
  std::unique_ptr<view::LiveView> live_;
};

// Returns when Ctrl-C (or SIGTERM) came (stop_on_signals): a page's server runs meanwhile.
void wait_for_signal();

std::unique_ptr<LiveViewSession> start_live_view(const ViewOption& option, run::Run& run, const std::string& title);

}  // namespace csp::cli
