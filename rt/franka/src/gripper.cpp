#include "franka/gripper.h"

#include "franka/exception.h"
#include "wall_clock_device.hpp"

namespace franka {

namespace {

// The research-interface version of the hand's server (libfranka-common gripper kVersion).
constexpr Gripper::ServerVersion kGripperServerVersion = 3;

}  // namespace

// The class holds only its opaque pointer: its layout never depends on the user's compile flags.
static_assert(sizeof(Gripper) == sizeof(void*), "franka::Gripper must hold nothing but its Impl pointer");

struct Gripper::Impl : csp::franka_support::WallClockDevice<csp::rt::Hand> {
  using WallClockDevice::WallClockDevice;
};

Gripper::Gripper(const std::string& franka_address)
    : impl_(std::make_unique<Impl>(franka_address, &csp::rt::Scenario::hand, "libfranka gripper")) {}
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

Gripper::ServerVersion Gripper::serverVersion() const noexcept { return kGripperServerVersion; }

std::ostream& operator<<(std::ostream& ostream, const GripperState& gripper_state) {
  return ostream << "{\"width\": " << gripper_state.width << ", \"max_width\": " << gripper_state.max_width
                 << ", \"is_grasped\": " << gripper_state.is_grasped << ", \"temperature\": " << gripper_state.temperature
                 << ", \"time\": " << gripper_state.time.toSec() << "}";
}

}  // namespace franka
