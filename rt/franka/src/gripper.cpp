#include "franka/gripper.h"

#include <filesystem>

#include "csp/rt/scenario.hpp"
#include "franka/exception.h"
#include "wall_clock_device.hpp"

namespace franka {

namespace {

// The hand of the robot at address: a scenario file's hand, else the Franka Hand with nothing
// between its fingers.
csp::rt::HandSettings hand_at(const std::string& address) {
  if (!std::filesystem::is_regular_file(address)) return {};
  try {
    return csp::rt::load_scenario(address).hand;
  } catch (const std::exception& e) {
    throw NetworkException(std::string("libfranka gripper: cannot reach the hand of ") + address + ": " + e.what());
  }
}

// The research-interface version of the hand's server (libfranka-common gripper kVersion).
constexpr Gripper::ServerVersion kServerVersion = 3;

}  // namespace

// The class holds only its opaque pointer: its layout never depends on the user's compile flags.
static_assert(sizeof(Gripper) == sizeof(void*), "franka::Gripper must hold nothing but its Impl pointer");

struct Gripper::Impl : WallClockDevice<csp::rt::Hand> {
  using WallClockDevice::WallClockDevice;
};

Gripper::Gripper(const std::string& franka_address)
    : impl_(std::make_unique<Impl>(hand_at(franka_address), "libfranka gripper")) {}
Gripper::Gripper(Gripper&&) noexcept = default;
Gripper& Gripper::operator=(Gripper&&) noexcept = default;
Gripper::~Gripper() noexcept = default;

bool Gripper::homing() const {
  return impl_->execute([](csp::rt::Hand& hand) { return hand.homing(); });
}

bool Gripper::grasp(double width, double speed, double force, double epsilon_inner, double epsilon_outer) const {
  return impl_->execute([&](csp::rt::Hand& hand) { return hand.grasp(width, speed, force, epsilon_inner, epsilon_outer); });
}

bool Gripper::move(double width, double speed) const {
  return impl_->execute([&](csp::rt::Hand& hand) { return hand.move(width, speed); });
}

bool Gripper::stop() const {
  return impl_->execute([](csp::rt::Hand& hand) { return hand.stop(); });
}

GripperState Gripper::readOnce() const {
  const csp::rt::HandState hand = impl_->read_once();
  GripperState state;
  state.width = hand.width;
  state.max_width = hand.max_width;
  state.is_grasped = hand.is_grasped;
  state.temperature = hand.temperature;
  state.time = Duration(hand.message_id);
  return state;
}

Gripper::ServerVersion Gripper::serverVersion() const noexcept { return kServerVersion; }

std::ostream& operator<<(std::ostream& ostream, const GripperState& gripper_state) {
  return ostream << "{\"width\": " << gripper_state.width << ", \"max_width\": " << gripper_state.max_width
                 << ", \"is_grasped\": " << gripper_state.is_grasped << ", \"temperature\": " << gripper_state.temperature
                 << ", \"time\": " << gripper_state.time.toSec() << "}";
}

}  // namespace franka
