// A device model (csp::rt::Hand, csp::rt::VacuumPump) run against the wall clock and shared
// between threads: every call first advances the model to now, so the device lives in real time
// whether or not anyone is calling. Commands block, polling each millisecond, until the model
// answers them, as libfranka's calls block until the device's server answers.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "csp/rt/hand.hpp"
#include "csp/rt/scenario.hpp"
#include "robot_address.hpp"
#include "franka/exception.h"

// Outside namespace franka: libcsp_franka.so exports libfranka's API only (package/franka.map).
namespace csp::franka_support {

using franka::CommandException;
using franka::InvalidOperationException;
using franka::NetworkException;

// The device of the robot at address, found as franka::Robot finds its robot (a scenario path, or an
// IP/hostname with $CSP_SCENARIO or the shipped libfranka_panda scenario): that scenario's section.
// A device the scenario does not mount (`mounted` false) cannot be connected to, as on a robot
// without it.
template <typename Settings>
Settings device_at(const std::string& address, Settings csp::rt::Scenario::*section, const std::string& who,
                   bool csp::rt::Scenario::*mounted = nullptr) {
  csp::rt::Scenario scenario;
  try {
    scenario = csp::rt::load_scenario(csp::franka_address::scenario_for_address(
        address, std::getenv("CSP_SCENARIO"), csp::rt::shipped_config_dir() + "/scenarios"));
  } catch (const std::exception& e) {
    throw NetworkException("libfranka: Connection to " + address + " failed: " + who + ": " + e.what());
  }
  if (mounted != nullptr && !(scenario.*mounted))
    throw NetworkException("libfranka: Connection to " + address + " failed: " + who +
                           ": the robot has no such device (its scenario has no section for it)");
  return scenario.*section;
}

template <typename Device>
class WallClockDevice {
 public:
  // The device of the robot at address (device_at); who: libfranka's message prefix, e.g.
  // "libfranka gripper".
  template <typename Settings>
  WallClockDevice(const std::string& address, Settings csp::rt::Scenario::*section, std::string who,
                  bool csp::rt::Scenario::*mounted = nullptr)
      : device_(device_at(address, section, who, mounted)), who_(std::move(who)), last_(std::chrono::steady_clock::now()) {}

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
