// Eigen values into RobotState's std::arrays (libfranka's layout: column-major matrices).
#pragma once

#include <array>

#include "csp/dynamics/model.hpp"

namespace csp::rt {

template <std::size_t N, typename Derived>
void assign(std::array<double, N>& out, const Eigen::MatrixBase<Derived>& value) {
  static_assert(Derived::SizeAtCompileTime == static_cast<int>(N));
  Eigen::Map<Eigen::Matrix<double, Derived::RowsAtCompileTime, Derived::ColsAtCompileTime>>(out.data()) = value;
}

inline void assign(std::array<double, 16>& out, const Transform& pose) { assign(out, pose.matrix()); }

inline void assign_inertia(const RigidBodyInertia& body, double& mass, std::array<double, 3>& com,
                           std::array<double, 9>& inertia) {
  mass = body.mass;
  assign(com, body.com);
  assign(inertia, body.inertia);
}

}  // namespace csp::rt
