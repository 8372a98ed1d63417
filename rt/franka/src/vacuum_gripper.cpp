#include "franka/vacuum_gripper.h"

#include "franka/exception.h"
#include "wall_clock_device.hpp"

namespace franka {

namespace {

// The research-interface version of the pump's server (libfranka-common vacuum_gripper kVersion).
constexpr VacuumGripper::ServerVersion kVacuumGripperServerVersion = 1;

double seconds(std::chrono::milliseconds duration) { return std::chrono::duration<double>(duration).count(); }

const char* status_name(VacuumGripperDeviceStatus status) {
  switch (status) {
    case VacuumGripperDeviceStatus::kGreen: return "Green";
    case VacuumGripperDeviceStatus::kYellow: return "Yellow";
    case VacuumGripperDeviceStatus::kOrange: return "Orange";
    case VacuumGripperDeviceStatus::kRed: return "Red";
  }
  return "Unknown";
}

}  // namespace

// The class holds only its opaque pointer: its layout never depends on the user's compile flags.
static_assert(sizeof(VacuumGripper) == sizeof(void*), "franka::VacuumGripper must hold nothing but its Impl pointer");

struct VacuumGripper::Impl : csp::franka_support::WallClockDevice<csp::rt::VacuumPump> {
  using WallClockDevice::WallClockDevice;
};

VacuumGripper::VacuumGripper(const std::string& franka_address)
    : impl_(std::make_unique<Impl>(franka_address, &csp::rt::Scenario::vacuum_gripper, "libfranka vacuum gripper",
                                     &csp::rt::Scenario::has_vacuum_gripper)) {}
VacuumGripper::VacuumGripper(VacuumGripper&&) noexcept = default;
VacuumGripper& VacuumGripper::operator=(VacuumGripper&&) noexcept = default;
VacuumGripper::~VacuumGripper() noexcept = default;

bool VacuumGripper::vacuum(uint8_t vacuum, std::chrono::milliseconds timeout, ProductionSetupProfile profile) const {
  return impl_->execute([&](csp::rt::VacuumPump& pump) {
    return pump.vacuum(vacuum, seconds(timeout), static_cast<csp::rt::VacuumProfile>(profile));
  });
}

bool VacuumGripper::dropOff(std::chrono::milliseconds timeout) const {
  return impl_->execute([&](csp::rt::VacuumPump& pump) { return pump.drop_off(seconds(timeout)); });
}

bool VacuumGripper::stop() const {
  return impl_->execute([](csp::rt::VacuumPump& pump) { return pump.stop(); });
}

VacuumGripperState VacuumGripper::readOnce() const {
  const csp::rt::VacuumState pump = impl_->read_once();
  VacuumGripperState state;
  state.in_control_range = pump.in_control_range;
  state.part_detached = pump.part_detached;
  state.part_present = pump.part_present;
  state.device_status = VacuumGripperDeviceStatus::kGreen;   // the model has no faults
  state.actual_power = pump.actual_power;
  state.vacuum = pump.vacuum;
  state.time = Duration(pump.message_id);
  return state;
}

VacuumGripper::ServerVersion VacuumGripper::serverVersion() const noexcept { return kVacuumGripperServerVersion; }

std::ostream& operator<<(std::ostream& ostream, const VacuumGripperState& state) {
  return ostream << "{\"in_control_range\": " << state.in_control_range << ", \"part_detached\": " << state.part_detached
                 << ", \"part_present\": " << state.part_present << ", \"device_status\": \""
                 << status_name(state.device_status) << "\", \"actual_power\": " << state.actual_power
                 << ", \"vacuum\": " << state.vacuum << ", \"time\": " << state.time.toSec() << "}";
}

}  // namespace franka
