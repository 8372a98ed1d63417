// Eigen values into RobotState's std::arrays: assign() from csp/dynamics/arrays.hpp, and the
// three fields (mass, CoM, inertia) RobotState keeps for each body on the flange.
#pragma once

#include <array>

#include "csp/dynamics/arrays.hpp"

namespace csp::rt {

inline void assign_inertia(const RigidBodyInertia& body, double& mass, std::array<double, 3>& com,
                           std::array<double, 9>& inertia) {
  mass = body.mass;
  assign(com, body.com);
  assign(inertia, body.inertia);
}

}  // namespace csp::rt
