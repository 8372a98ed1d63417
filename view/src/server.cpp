#include "csp/view/server.hpp"

#include <dlfcn.h>

#include <civetweb.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace csp::view {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool is_folder(const fs::path& path) {
  std::error_code error;
  return fs::is_directory(path, error);
}

// The installed layout: <prefix>/share/csp/view/{web,three,uplot,meshes}, next to the library.
fs::path installed_view_dir() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&view_files), &info) != 0 && info.dli_fname != nullptr)
    return fs::path(info.dli_fname).parent_path().parent_path() / "share" / "csp" / "view";
  return CSP_INSTALLED_VIEW_DIR;
}

ViewFiles files_in(const fs::path& dir) {
  return {(dir / "web").string(), (dir / "three").string(), (dir / "uplot").string(), (dir / "meshes").string()};
}

ViewFiles checked(ViewFiles files, const std::string& where) {
  const std::pair<const std::string*, const char*> needed[] = {
      {&files.page, "the page (index.html)"}, {&files.three, "three.js"}, {&files.uplot, "uPlot"}, {&files.meshes, "Franka's meshes"}};
  for (const auto& [dir, what] : needed)
    if (!is_folder(*dir))
      throw std::runtime_error("csp view: " + std::string(what) + " not found at " + *dir + " (" + where + ")");
  return files;
}

const char* mime_type(const fs::path& file) {
  const std::string extension = file.extension().string();
  if (extension == ".html") return "text/html; charset=utf-8";
  if (extension == ".js" || extension == ".mjs") return "text/javascript";   // ES modules need a JavaScript type
  if (extension == ".css") return "text/css";
  if (extension == ".json") return "application/json";
  if (extension == ".png") return "image/png";
  if (extension == ".dae") return "model/vnd.collada+xml";
  if (extension == ".stl") return "model/stl";
  return "application/octet-stream";
}

void send(mg_connection* connection, int status, const char* type, const std::string& body) {
  mg_printf(connection,
            "HTTP/1.1 %d %s\r\nContent-Type: %s\r\nContent-Length: %zu\r\nCache-Control: no-store\r\n"
            "Connection: close\r\n\r\n",
            status, mg_get_response_code_text(connection, status), type, body.size());
  mg_write(connection, body.data(), body.size());
}

int send_json(mg_connection* connection, int status, const json& body) {
  send(connection, status, "application/json", body.dump());
  return status;
}

int send_error(mg_connection* connection, int status, const std::string& message) {
  return send_json(connection, status, {{"error", message}});
}

// The file `relative` under `root`, if it is one and stays under it (the URI is already cleaned of
// "..", civetweb's local_uri; this also refuses a symbolic link out of the folder).
std::optional<fs::path> file_under(const std::string& root, const std::string& relative) {
  std::error_code error;
  const fs::path base = fs::weakly_canonical(root, error);
  const fs::path file = fs::weakly_canonical(base / relative, error);
  if (error || !fs::is_regular_file(file, error)) return std::nullopt;
  const auto [end, unused] = std::mismatch(base.begin(), base.end(), file.begin(), file.end());
  if (end != base.end()) return std::nullopt;
  return file;
}

// civetweb's messages while it starts (the port is taken): said in the exception. mg_start runs in
// the constructing thread, so a thread-local keeps two servers starting at once apart.
thread_local std::string start_log;

int log_message(const mg_connection*, const char* message) {
  if (!start_log.empty()) start_log += "; ";
  start_log += message;
  return 1;   // handled: civetweb prints nothing itself
}

}  // namespace

ViewFiles view_files() {
  if (const char* dir = std::getenv("CSP_VIEW_DIR"); dir != nullptr && *dir != '\0')
    return checked(files_in(dir), "CSP_VIEW_DIR");
  const fs::path source = fs::path(CSP_SOURCE_DIR) / "view" / "web";
  if (is_folder(source))
    return checked({source.string(), (source / "node_modules" / "three").string(),
                    (source / "node_modules" / "uplot" / "dist").string(), CSP_MESH_DIR},
                   "the source tree's view/web: run `npm ci --prefix view/web` for its packages");
  return checked(files_in(installed_view_dir()), "the installed share/csp/view");
}

ViewServer::ViewServer(const std::string& address, int port, json description)
    : files_(view_files()), description_(std::move(description)) {
  if (port < 0 || port > 65535) throw std::runtime_error("csp view: port " + std::to_string(port) + ": expected 0..65535");
  const std::string listening = address + ":" + std::to_string(port);
  // Enough worker threads for a page loading its files in parallel while live pages hold theirs.
  const char* options[] = {"listening_ports", listening.c_str(), "num_threads", "16", "request_timeout_ms", "10000",
                           "websocket_timeout_ms", "3600000", "enable_websocket_ping_pong", "yes", nullptr};
  mg_callbacks callbacks{};
  callbacks.log_message = log_message;
  start_log.clear();
  context_ = mg_start(&callbacks, this, options);
  if (context_ == nullptr)
    throw std::runtime_error("csp view: cannot listen on " + listening + (start_log.empty() ? "" : ": " + start_log));
  start_log.clear();
  mg_server_port ports[4]{};
  const int count = mg_get_server_ports(context_, 4, ports);
  url_ = "http://" + address + ":" + std::to_string(count > 0 ? ports[0].port : port) + "/";
  mg_set_request_handler(context_, "/", handle_request, this);
  mg_set_websocket_handler(context_, "/api/live", handle_live_connect, handle_live_ready, handle_live_data,
                           handle_live_close, this);
}

ViewServer::~ViewServer() { mg_stop(context_); }

std::string ViewServer::url() const { return url_; }

void ViewServer::set_recording(std::shared_ptr<const Recording> recording) {
  const std::lock_guard lock(mutex_);
  recording_ = std::move(recording);
}

int ViewServer::broadcast(const std::string& message) {
  const std::lock_guard lock(mutex_);
  int reached = 0;
  for (auto page = pages_.begin(); page != pages_.end();) {
    if (mg_websocket_write(*page, MG_WEBSOCKET_OPCODE_TEXT, message.data(), message.size()) > 0) {
      ++reached;
      ++page;
    } else {
      page = pages_.erase(page);   // closed: civetweb's close handler finds it gone
    }
  }
  return reached;
}

bool ViewServer::has_recording() const {
  const std::lock_guard lock(mutex_);
  return recording_ != nullptr;
}

int ViewServer::pages() const {
  const std::lock_guard lock(mutex_);
  return static_cast<int>(pages_.size());
}

int ViewServer::handle_request(mg_connection* connection, void* self) {
  const mg_request_info* request = mg_get_request_info(connection);
  const std::string path = request->local_uri != nullptr ? request->local_uri : "/";
  if (std::string(request->request_method) != "GET") return send_error(connection, 405, "csp view answers GET only");
  try {
    return static_cast<ViewServer*>(self)->answer(connection, path, request->query_string ? request->query_string : "");
  } catch (const std::exception& error) {   // a bug or an exhausted machine: the page says it, the server goes on
    return send_error(connection, 500, error.what());
  }
}

int ViewServer::answer(mg_connection* connection, const std::string& path, const std::string& query) {
  if (path == "/api/description") return send_json(connection, 200, description_);
  if (path == "/api/recording" || path == "/api/series") {
    std::shared_ptr<const Recording> recording;
    {
      const std::lock_guard lock(mutex_);
      recording = recording_;
    }
    if (!recording) return send_error(connection, 404, "no recorded run yet (a live run is shown as it happens)");
    if (path == "/api/recording")
      return send_json(connection, 200,
                       {{"source", recording->source}, {"frames", recording->frames}, {"events", recording->events},
                        {"columns", column_names(*recording)}});
    std::vector<char> text(query.size() + 1);
    if (mg_get_var(query.c_str(), query.size(), "names", text.data(), text.size()) <= 0)
      return send_error(connection, 400, "/api/series: expected ?names=COLUMN,COLUMN,...");
    std::vector<std::string> names;
    for (std::string_view list = text.data(); !list.empty();) {
      const std::size_t comma = std::min(list.find(','), list.size());
      names.emplace_back(list.substr(0, comma));
      list.remove_prefix(std::min(comma + 1, list.size()));
    }
    try {
      return send_json(connection, 200, series(*recording, names));
    } catch (const std::out_of_range& error) {
      return send_error(connection, 404, error.what());
    }
  }
  // The files: the page, the libraries, the meshes.
  const std::pair<const char*, const std::string*> roots[] = {
      {"/vendor/three/", &files_.three}, {"/vendor/uplot/", &files_.uplot}, {"/meshes/", &files_.meshes}};
  std::string root = files_.page, relative = path == "/" ? "index.html" : path.substr(1);
  for (const auto& [prefix, dir] : roots) {
    if (path.rfind(prefix, 0) == 0) {
      root = *dir;
      relative = path.substr(std::string(prefix).size());
    }
  }
  const std::optional<fs::path> file = file_under(root, relative);
  if (!file) return send_error(connection, 404, "no file " + path);
  mg_send_mime_file(connection, file->c_str(), mime_type(*file));
  return 200;
}

int ViewServer::handle_live_connect(const mg_connection*, void*) { return 0; }   // 0: accept

void ViewServer::handle_live_ready(mg_connection* connection, void* self) {
  auto* server = static_cast<ViewServer*>(self);
  std::size_t pages = 0;
  {
    const std::lock_guard lock(server->mutex_);
    server->pages_.insert(connection);
    pages = server->pages_.size();
  }
  server->notice("a page connected (" + std::to_string(pages) + " open)");
}

int ViewServer::handle_live_data(mg_connection*, int, char*, std::size_t, void*) { return 1; }   // 1: keep it open

void ViewServer::handle_live_close(const mg_connection* connection, void* self) {
  auto* server = static_cast<ViewServer*>(self);
  std::size_t pages = 0;
  {
    const std::lock_guard lock(server->mutex_);
    server->pages_.erase(const_cast<mg_connection*>(connection));
    pages = server->pages_.size();
  }
  server->notice("a page closed its connection (" + std::to_string(pages) + " open)");
}

}  // namespace csp::view
