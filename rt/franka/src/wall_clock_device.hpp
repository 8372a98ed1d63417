// A device model (csp::rt::Hand, csp::rt::VacuumPump) run against the wall clock and shared
// between threads: every call first advances the model to now, so the device lives in real time
// whether or not anyone is calling. Commands block, polling each millisecond, until the model
// answers them, as libfranka's calls block until the device's server answers.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "csp/rt/hand.hpp"
#include "csp/rt/scenario.hpp"
#include "franka/exception.h"

// Outside namespace franka: libcsp_franka.so exports libfranka's API only (package/franka.map).
namespace csp::franka_support {

using franka::CommandException;
using franka::InvalidOperationException;
using franka::NetworkException;

// The device of the robot at address: the section of a scenario file given as address, or the
// default device (nothing held) for any other address, e.g. an IP.
template <typename Settings>
Settings device_at(const std::string& address, Settings csp::rt::Scenario::*section, const std::string& who) {
  if (!std::filesystem::is_regular_file(address)) return {};
  try {
    return csp::rt::load_scenario(address).*section;
  } catch (const std::exception& e) {
    throw NetworkException(who + ": cannot reach the device of " + address + ": " + e.what());
  }
}

template <typename Device>
class WallClockDevice {
 public:
  // The device of the robot at address (device_at); who: libfranka's message prefix, e.g.
  // "libfranka gripper".
  template <typename Settings>
  WallClockDevice(const std::string& address, Settings csp::rt::Scenario::*section, std::string who)
      : device_(device_at(address, section, who)), who_(std::move(who)), last_(std::chrono::steady_clock::now()) {}

  // Issues a command with issue(device) and waits for its answer: true on success, false when
  // unsuccessful, CommandException when refused or aborted.
  template <typename Issue>
  bool execute(Issue issue) {
    uint64_t id = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      catch_up();
      try {
        id = issue(device_);
      } catch (const csp::rt::CommandRefused& refused) {
        throw CommandException(who_ + ": Command failed! " + refused.what());
      }
    }
    csp::rt::CommandStatus status = csp::rt::CommandStatus::kRunning;
    while (status == csp::rt::CommandStatus::kRunning) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      std::lock_guard<std::mutex> lock(mutex_);
      catch_up();
      status = device_.answer(id);
    }
    if (status == csp::rt::CommandStatus::kAborted) throw CommandException(who_ + ": Command aborted!");
    return status == csp::rt::CommandStatus::kSuccess;
  }

  // Waits for the device's next state message (libfranka drops older ones) and returns it.
  auto read_once() {
    if (reading_.exchange(true)) throw InvalidOperationException(who_ + ": another readOnce is already running");
    struct Done {
      std::atomic<bool>& flag;
      ~Done() { flag = false; }
    } done{reading_};
    std::unique_lock<std::mutex> lock(mutex_);
    catch_up();
    const uint64_t seen = device_.published_state().message_id;
    while (device_.published_state().message_id == seen) {
      const auto wait = std::chrono::duration<double>(device_.time_to_next_state());
      lock.unlock();
      std::this_thread::sleep_for(wait);
      lock.lock();
      catch_up();
    }
    return device_.published_state();
  }

 private:
  void catch_up() {
    const auto now = std::chrono::steady_clock::now();
    device_.step(std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

  std::mutex mutex_;
  Device device_;
  std::string who_;
  std::chrono::steady_clock::time_point last_;
  std::atomic<bool> reading_{false};
};

}  // namespace csp::franka_support
