// franka::VacuumGripper: the Cobot Pump of the emulated robot, behind libfranka's VacuumGripper
// interface. Commands block for as long as the pump takes (wall time). The model:
// csp::rt::VacuumPump, docs/gripper.md.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "franka/vacuum_gripper_state.h"

namespace franka {

class VacuumGripper {
 public:
  using ServerVersion = uint16_t;

  // The pump's production setup profiles P0 to P3.
  enum class ProductionSetupProfile { kP0, kP1, kP2, kP3 };

  // The pump of the robot at franka_address: a scenario file's `vacuum_gripper:` section, or a
  // pump with no part under its cup for any other address. Throws NetworkException if the
  // scenario cannot be loaded.
  explicit VacuumGripper(const std::string& franka_address);
  VacuumGripper(VacuumGripper&& vacuum_gripper) noexcept;
  VacuumGripper& operator=(VacuumGripper&& vacuum_gripper) noexcept;
  ~VacuumGripper() noexcept;
  VacuumGripper(const VacuumGripper&) = delete;
  VacuumGripper& operator=(const VacuumGripper&) = delete;

  // Sucks at the setpoint [10 mbar]; true once the vacuum is in its control range, false if the
  // timeout passes first.
  bool vacuum(uint8_t vacuum, std::chrono::milliseconds timeout,
              ProductionSetupProfile profile = ProductionSetupProfile::kP0) const;
  // Blows the part off; true once it is detached, false if the timeout passes first.
  bool dropOff(std::chrono::milliseconds timeout) const;
  // Ends a running vacuum or dropOff and switches the pump off.
  bool stop() const;
  // Waits for the pump's next state message and returns it.
  VacuumGripperState readOnce() const;
  ServerVersion serverVersion() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace franka
