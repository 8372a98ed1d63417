// Helpers of the bridge tests: child processes, per-test LCM URLs, temporary files, logs.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "csp/bridge/lcm_log.hpp"

extern char** environ;

namespace csp::test {

// A multicast port of its own for each test of each process: parallel ctest runs do not talk to
// each other.
inline std::string unique_lcm_url(int n) {
  return "udpm://239.255.76.67:" + std::to_string(7667 + 1 + static_cast<int>(getpid() % 2000) * 8 + n) + "?ttl=0";
}

inline std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("csp-bridge-test-" + std::to_string(getpid()) + "-" + name)).string();
}

// A child process with stdout and stderr to a file; killed if still running when destroyed.
class Process {
 public:
  explicit Process(const std::vector<std::string>& argv, const std::string& output)
      : output_(output) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int error = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  // The exit code, or -1 if the process has not ended within `timeout` (it is then killed).
  int wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }
  void signal(int number) { kill(pid_, number); }
  std::string output() const {
    std::ifstream in(output_);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }

 private:
  pid_t pid_ = -1;
  std::string output_;
};

// The robot states of a log's channel, in order.
inline std::vector<robot_state_t> states_in_log(const std::string& path, const std::string& channel = "CSP_STATE") {
  bridge::LogReader log(path);
  std::vector<robot_state_t> states;
  for (const bridge::LogEvent* e = log.next(); e; e = log.next()) {
    if (e->channel != channel) continue;
    robot_state_t m;
    if (bridge::decode_exact(e->data, e->datalen, m) != bridge::Rejection::kNone) throw std::runtime_error("bad state in " + path);
    states.push_back(m);
  }
  return states;
}

// Publishes `marker` on TEST_MARKER every 50 ms until the log being written at `path` holds it;
// false after 20 s.
inline bool wait_until_logged(lcm::LCM& lcm, const std::string& path, const std::string& marker) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    lcm.publish("TEST_MARKER", marker.data(), static_cast<unsigned>(marker.size()));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (!std::filesystem::exists(path)) continue;
    bridge::LogReader log(path);   // a partly written last event reads as the end of the log
    for (const bridge::LogEvent* e = log.next(); e; e = log.next())
      if (e->channel == "TEST_MARKER" && std::string(static_cast<const char*>(e->data), e->datalen) == marker) return true;
  }
  return false;
}

}  // namespace csp::test
