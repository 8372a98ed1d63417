// The built-in controllers a scenario can run (`csp emulate`), written against the robot's own
// model as a libfranka controller would use franka::Model.
#pragma once

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::rt {

struct BuiltinController {
  ControlMode mode;
  Controller controller;
  std::shared_ptr<const MedicalStatus> status;   // what a medical controller found (breakthrough)
};

// The joint_impedance law (libfranka's joint_impedance_control example, plus the model's
// feed-forward when spec.feedforward): tau = K (q_d - q) + D (dq_d - dq) [+ M(q) ddq_d + c(q, dq)],
// without gravity (the robot adds it); `model` is the robot's own (a libfranka controller's
// franka::Model), K and D are spec.stiffness and spec.damping.
Vector7 joint_impedance_torque(const Model& model, Data& data, const ControllerSpec& spec, const Vector7& q_d,
                               const Vector7& dq_d, const Vector7& ddq_d, const RobotState& state);

// The controller of `spec`, starting from the emulator's current state; `faults` make it throw
// or return NaN at the given motion times.
BuiltinController make_controller(const ControllerSpec& spec, const ControllerFaults& faults, const Emulator& emulator);

}  // namespace csp::rt
