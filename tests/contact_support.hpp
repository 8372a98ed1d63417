// The ultrasound scene's probe pressing on the breathing abdomen: the emulator settings and a
// torque controller, shared by the no-allocation test and the contact benchmark.
#pragma once

#include <algorithm>
#include <memory>
#include <string>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/emulator.hpp"

namespace csp::test {

inline std::shared_ptr<const Scene> shipped_ultrasound_scene() {
  static const auto scene = std::make_shared<const Scene>(load_scene(std::string(CSP_SOURCE_DIR) + "/configs/scenes/ultrasound_abdomen.yaml"));
  return scene;
}

// Every contact and collision threshold at 100, as libfranka's force_control example sets them
// before it presses.
inline void raise_collision_thresholds(rt::CollisionBehavior& c) {
  for (Vector7* v : {&c.lower_torque_acceleration, &c.upper_torque_acceleration, &c.lower_torque_nominal, &c.upper_torque_nominal})
    v->setConstant(100.0);
  for (Vector6* v : {&c.lower_force_acceleration, &c.upper_force_acceleration, &c.lower_force_nominal, &c.upper_force_nominal})
    v->setConstant(100.0);
}

// `base`'s plant and robot model carrying the scene's probe, at the scan's start pose (the TCP
// 8 cm above the skin), thresholds raised as libfranka's force_control example does; with the
// scene when `contact`.
inline rt::EmulatorSettings ultrasound_settings(rt::EmulatorSettings base, bool contact) {
  const auto scene = shipped_ultrasound_scene();
  base.plant = with_tool(base.plant, scene->tool);
  base.internal = with_tool(base.internal, scene->tool);
  base.q_initial = scene->pose("scan_start_hover").q;
  base.external_wrenches.clear();
  raise_collision_thresholds(base.collision);
  if (contact) base.scene = scene;
  return base;
}

// The torque that makes the TCP push with `force` (what the robot exerts on its environment, base
// frame) with joint damping: tau = J^T (force; 0) - 5 dq. At rest the TCP's wrench is `force`.
// No allocation.
inline Vector7 pressing_torque(const Model& model, Data& data, const rt::RobotState& state, const Vector3& force) {
  const Vector7 q(state.q.data()), dq(state.dq.data());
  forward_kinematics(model, data, q);
  Matrix6x7 jacobian;
  zero_jacobian(data, Frame::kEndEffector, jacobian);
  return jacobian.topRows<3>().transpose() * force - 5.0 * dq;
}

// pressing_torque with `force` ramped in over the first 0.5 s (libfranka's torque-rate limit).
class PressingController {
 public:
  PressingController(const Model& model, const Vector3& force) : model_(model), force_(force) {}

  rt::Command operator()(const rt::RobotState& state) {
    const double ramp = std::min(1.0, ++cycles_ / 500.0);
    return {pressing_torque(model_, data_, state, ramp * force_), false};
  }

 private:
  const Model& model_;
  Vector3 force_;
  Data data_;
  int cycles_ = 0;
};

}  // namespace csp::test
