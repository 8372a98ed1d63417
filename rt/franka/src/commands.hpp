// A franka command as the robot receives it (csp::rt::Command), after libfranka's checks; shared by
// control() and the external control loop.
#pragma once

#include "csp/dynamics/arrays.hpp"
#include "csp/rt/emulator.hpp"
#include "franka/control_tools.h"
#include "franka/control_types.h"

namespace franka::commands {

using csp::from_array;

inline void set(csp::rt::Command& c, const Torques& t) { c.values = from_array<csp::Vector7>(t.tau_J); }
inline void set(csp::rt::Command& c, const JointPositions& p) { c.values = from_array<csp::Vector7>(p.q); }
inline void set(csp::rt::Command& c, const JointVelocities& v) { c.values = from_array<csp::Vector7>(v.dq); }
inline void set(csp::rt::Command& c, const CartesianPose& p) {
  c.O_T_EE_c = p.O_T_EE;
  if (p.hasElbow()) c.elbow = p.elbow;
}
inline void set(csp::rt::Command& c, const CartesianVelocities& v) {
  c.O_dP_EE_c = v.O_dP_EE;
  if (v.hasElbow()) c.elbow = v.elbow;
}

// libfranka's checks before a command is sent: std::invalid_argument for NaN or infinite values
// (and, for a pose, a matrix that is not a homogeneous transform; for an elbow, a sign not +-1).
inline void check(const Torques& t) { checkFinite(t.tau_J); }
inline void check(const JointPositions& p) { checkFinite(p.q); }
inline void check(const JointVelocities& v) { checkFinite(v.dq); }
inline void check(const CartesianPose& p) {
  checkMatrix(p.O_T_EE);
  if (p.hasElbow()) checkElbow(p.elbow);
}
inline void check(const CartesianVelocities& v) {
  checkFinite(v.O_dP_EE);
  if (v.hasElbow()) checkElbow(v.elbow);
}

}  // namespace franka::commands
