// Eigen values <-> plain arrays of doubles in libfranka's layout: matrices column-major (a pose as
// its 4x4 homogeneous matrix in 16 numbers, a 6x7 Jacobian in 42), vectors in order. The one
// place where RobotState, the libfranka-shaped API, the LCM messages and the command line meet
// the math types.
#pragma once

#include <array>
#include <cstddef>
#include <optional>

#include "csp/dynamics/spatial.hpp"

namespace csp {

// Writes a fixed-size Eigen vector or matrix into `out`, column-major.
template <std::size_t N, typename Derived>
void assign(std::array<double, N>& out, const Eigen::MatrixBase<Derived>& value) {
  static_assert(Derived::SizeAtCompileTime == static_cast<int>(N), "the array has another size than the matrix");
  Eigen::Map<Eigen::Matrix<double, Derived::RowsAtCompileTime, Derived::ColsAtCompileTime>>(out.data()) = value;
}

// Writes a pose as its 4x4 homogeneous matrix, column-major.
inline void assign(std::array<double, 16>& out, const Transform& pose) { assign(out, pose.matrix()); }

// The array of a fixed-size Eigen vector or matrix, column-major.
template <typename Derived>
std::array<double, static_cast<std::size_t>(Derived::SizeAtCompileTime)> to_array(const Eigen::MatrixBase<Derived>& value) {
  std::array<double, static_cast<std::size_t>(Derived::SizeAtCompileTime)> out;
  assign(out, value);
  return out;
}

inline std::array<double, 16> to_array(const Transform& pose) { return to_array(pose.matrix()); }

// The fixed-size Eigen vector or matrix `Matrix` of column-major values: from an std::array or
// a C array of the right size (from_array), or from a pointer to as many values (from_data).
template <typename Matrix>
Matrix from_data(const double* column_major) {
  return Eigen::Map<const Matrix>(column_major);
}

template <typename Matrix, std::size_t N>
Matrix from_array(const std::array<double, N>& column_major) {
  static_assert(Matrix::SizeAtCompileTime == static_cast<int>(N), "the array has another size than the matrix");
  return from_data<Matrix>(column_major.data());
}

template <typename Matrix, std::size_t N>
Matrix from_array(const double (&column_major)[N]) {
  static_assert(Matrix::SizeAtCompileTime == static_cast<int>(N), "the array has another size than the matrix");
  return from_data<Matrix>(column_major);
}

// The pose of a 4x4 homogeneous matrix (the inverse of Transform::matrix(); the bottom row is not
// read), and of its 16 values column-major.
inline Transform transform_from_matrix(const Eigen::Matrix4d& m) { return {m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>()}; }

inline Transform transform_from_array(const std::array<double, 16>& column_major) {
  return transform_from_matrix(from_array<Eigen::Matrix4d>(column_major));
}

// The pose of a 4x4 homogeneous matrix received from outside (setEE, setK over a bus): nullopt
// unless it is finite and rigid (rotation orthonormal to 1e-6 with determinant +1, bottom row
// 0 0 0 1).
inline std::optional<Transform> rigid_transform_from_matrix(const Eigen::Matrix4d& m) {
  const Matrix3 rotation = m.topLeftCorner<3, 3>();
  const bool rigid = m.allFinite() && m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)) &&
                     (rotation.transpose() * rotation).isApprox(Matrix3::Identity(), 1e-6) && rotation.determinant() > 0.0;
  if (!rigid) return std::nullopt;
  return transform_from_matrix(m);
}

}  // namespace csp
