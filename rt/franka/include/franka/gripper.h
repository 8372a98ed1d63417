// franka::Gripper: the Franka Hand of the emulated robot, behind libfranka's Gripper interface.
// Commands block for as long as the hand takes (wall time), answer as the hand's server does
// (true / false / CommandException) and may be called from several threads (stop() ends a move
// or grasp running in another). Arguments the hand refuses throw CommandException
// "libfranka gripper: Command failed!" followed by what was wrong; a command that another one
// replaced throws "libfranka gripper: Command aborted!". The model: csp::rt::Hand, docs/gripper.md.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "franka/gripper_state.h"

namespace franka {

class Gripper {
 public:
  using ServerVersion = uint16_t;

  // The hand of the robot at franka_address: a scenario file's `hand:` section, or the Franka Hand
  // with nothing between its fingers for any other address. Throws NetworkException if the
  // scenario cannot be loaded.
  explicit Gripper(const std::string& franka_address);
  Gripper(Gripper&& gripper) noexcept;
  Gripper& operator=(Gripper&& gripper) noexcept;
  ~Gripper() noexcept;
  Gripper(const Gripper&) = delete;
  Gripper& operator=(const Gripper&) = delete;

  // Closes and opens the fingers fully to measure max_width. True on success.
  bool homing() const;
  // Closes (or opens) at speed [m/s] until the fingers stop, holding with force [N]; true iff they
  // stop at a width d with width - epsilon_inner < d < width + epsilon_outer [m].
  bool grasp(double width, double speed, double force, double epsilon_inner = 0.005,
             double epsilon_outer = 0.005) const;
  // Moves the fingers to width [m] at speed [m/s]; false if something stops them.
  bool move(double width, double speed) const;
  // Ends a running move or grasp and releases the grip.
  bool stop() const;
  // Waits for the hand's next state message and returns it.
  GripperState readOnce() const;
  ServerVersion serverVersion() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace franka
