// csp view's web server (docs/view.md): the page and its files (three.js, uPlot and Franka's meshes,
// all served from this machine: the page works offline), the view's data as JSON, and the live run
// over a WebSocket. civetweb (Debian's libcivetweb-dev) does HTTP and WebSocket; this class only
// says what each address answers.
//
//   GET /                      the page (view/web/index.html and its scripts)
//   GET /vendor/three/...      three.js (npm, pinned in view/web/package.json)
//   GET /vendor/uplot/...      uPlot
//   GET /meshes/...            Franka's meshes (franka_description, Apache-2.0)
//   GET /api/description       the robot and scene (ViewModel::description), the title, live or not
//   GET /api/recording         the recorded run: frames, events, column names (404 until there is one)
//   GET /api/series?names=A,B  columns as one plot's series
//   WS  /api/live              a live run's frames, then {"type": "end"} when the run ends
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "csp/view/recording.hpp"

struct mg_context;
struct mg_connection;

namespace csp::view {

// Where the page's files are: $CSP_VIEW_DIR (a folder holding web/, three/, uplot/ and meshes/, as
// installed), else the source tree's view/web with its npm packages and the shared meshes, else the
// installed share/csp/view. Throws std::runtime_error naming what is missing and the command that
// gets it (npm ci --prefix view/web).
struct ViewFiles {
  std::string page, three, uplot, meshes;
};
ViewFiles view_files();

class ViewServer {
 public:
  // Listens on address:port (port 0: a free port the system picks). Throws std::runtime_error naming
  // the address when it cannot listen (the port is taken, the address is not this machine's).
  ViewServer(const std::string& address, int port, nlohmann::json description);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  std::string url() const;   // http://address:port/

  // The recorded run the page plays (replaces the one before; the page reloads it when told).
  void set_recording(std::shared_ptr<const Recording> recording);
  // A text message to every live page; a page whose connection fails is dropped. Returns how many
  // pages it reached.
  int broadcast(const std::string& message);
  int pages() const;   // live pages connected now
  bool has_recording() const;

  // Called (from the server's threads) with one line for the terminal: a page connected or left.
  void on_notice(std::function<void(const std::string&)> notice) { notice_ = std::move(notice); }

 private:
  static int handle_request(mg_connection* connection, void* self);
  static int handle_live_connect(const mg_connection* connection, void* self);
  static void handle_live_ready(mg_connection* connection, void* self);
  static int handle_live_data(mg_connection* connection, int flags, char* data, std::size_t length, void* self);
  static void handle_live_close(const mg_connection* connection, void* self);
  int answer(mg_connection* connection, const std::string& path, const std::string& query);
  void notice(const std::string& line) const {
    if (notice_) notice_(line);
  }

  ViewFiles files_;
  nlohmann::json description_;
  std::string url_;
  mutable std::mutex mutex_;   // recording_ and pages_
  std::shared_ptr<const Recording> recording_;
  std::set<mg_connection*> pages_;
  std::function<void(const std::string&)> notice_;
  mg_context* context_ = nullptr;
};

}  // namespace csp::view
