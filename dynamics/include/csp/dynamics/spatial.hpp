// Small spatial-algebra layer (Featherstone, "Rigid Body Dynamics Algorithms", ch. 2), with
// 6-vectors stored LINEAR FIRST as in libfranka and Pinocchio:
//   motion  v = (u; w): linear velocity of the point at the frame origin, angular velocity
//   force   f = (f; n): force, moment about the frame origin
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace csp {

constexpr int kNumJoints = 7;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector7 = Eigen::Matrix<double, kNumJoints, 1>;
using Matrix7 = Eigen::Matrix<double, kNumJoints, kNumJoints>;
using Matrix6x7 = Eigen::Matrix<double, 6, kNumJoints>;
using Matrix3x7 = Eigen::Matrix<double, 3, kNumJoints>;

inline Matrix3 skew(const Vector3& v) {
  Matrix3 s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

// Rigid transform a_T_b: the pose of frame b in frame a.
struct Transform {
  Matrix3 rotation = Matrix3::Identity();    // a_R_b
  Vector3 translation = Vector3::Zero();     // origin of b, in a

  Transform operator*(const Transform& b_T_c) const {
    return {rotation * b_T_c.rotation, rotation * b_T_c.translation + translation};
  }
  Vector3 operator*(const Vector3& point_in_b) const { return rotation * point_in_b + translation; }
  Eigen::Matrix4d matrix() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotation;
    m.topRightCorner<3, 1>() = translation;
    return m;
  }
};

inline Vector6 linear_angular(const Vector3& linear, const Vector3& angular) {
  Vector6 v;
  v << linear, angular;
  return v;
}

// v x m for two motion vectors (Featherstone eq. 2.31, linear-first).
inline Vector6 cross_motion(const Vector6& v, const Vector6& m) {
  const Vector3 u = v.head<3>(), w = v.tail<3>();
  return linear_angular(w.cross(m.head<3>()) + u.cross(m.tail<3>()), w.cross(m.tail<3>()));
}

// v x* f for a motion and a force vector (Featherstone eq. 2.32, linear-first).
inline Vector6 cross_force(const Vector6& v, const Vector6& f) {
  const Vector3 u = v.head<3>(), w = v.tail<3>();
  return linear_angular(w.cross(f.head<3>()), u.cross(f.head<3>()) + w.cross(f.tail<3>()));
}

// The 6x6 matrices of v x (.) and v x* (.).
inline Matrix6 cross_motion_matrix(const Vector6& v) {
  Matrix6 x = Matrix6::Zero();
  x.topLeftCorner<3, 3>() = x.bottomRightCorner<3, 3>() = skew(v.tail<3>());
  x.topRightCorner<3, 3>() = skew(v.head<3>());
  return x;
}
inline Matrix6 cross_force_matrix(const Vector6& v) { return -cross_motion_matrix(v).transpose(); }

// The matrix of v -> v x* f for a fixed force f (the "bar" operator of Echeandia & Wensing 2021).
inline Matrix6 cross_force_bar_matrix(const Vector6& f) {
  Matrix6 x = Matrix6::Zero();
  x.topRightCorner<3, 3>() = x.bottomLeftCorner<3, 3>() = -skew(f.head<3>());
  x.bottomRightCorner<3, 3>() = -skew(f.tail<3>());
  return x;
}

// Inertia of one rigid body as identified: mass, centre of mass and rotational inertia about
// the centre of mass, both in the coordinates of the body's frame.
struct RigidBodyInertia {
  double mass = 0.0;
  Vector3 com = Vector3::Zero();
  Matrix3 inertia = Matrix3::Zero();
};

// Spatial inertia about a frame origin, in that frame (Featherstone eq. 2.63):
//   [ m 1     -[h]x ]      h = m c (first moment of mass)
//   [ [h]x     I_O  ]      I_O = I_C - m [c]x [c]x (rotational inertia about the origin)
struct SpatialInertia {
  double mass = 0.0;
  Vector3 first_moment = Vector3::Zero();
  Matrix3 rotational = Matrix3::Zero();

  static SpatialInertia from(const RigidBodyInertia& body) {
    const Matrix3 c = skew(body.com);
    return {body.mass, body.mass * body.com, body.inertia - body.mass * c * c};
  }

  // Momentum (force-like) of the body moving with velocity v.
  Vector6 operator*(const Vector6& v) const {
    const Vector3 u = v.head<3>(), w = v.tail<3>();
    return linear_angular(mass * u - first_moment.cross(w), rotational * w + first_moment.cross(u));
  }

  SpatialInertia& operator+=(const SpatialInertia& other) {
    mass += other.mass;
    first_moment += other.first_moment;
    rotational += other.rotational;
    return *this;
  }

  // The same body expressed in frame a, given a_T_b with this inertia in frame b.
  SpatialInertia expressed_in(const Transform& a_T_b) const {
    const Matrix3& R = a_T_b.rotation;
    return SpatialInertia{mass, R * first_moment, R * rotational * R.transpose()}.shifted(a_T_b.translation);
  }

  // The same body about an origin moved to -p, i.e. in a frame whose origin sees this one at p
  // (axes unchanged). Parallel axis: -[h]x[p]x - [p]x[h]x - m [p]x^2, which with
  // [a]x[b]x = b a^T - (a.b) 1 and g = h + m p is (2 h.p + m p.p) 1 - p g^T - h p^T.
  SpatialInertia shifted(const Vector3& p) const {
    const Vector3& h = first_moment;
    const Vector3 g = h + mass * p;
    const double diagonal = 2.0 * h.dot(p) + mass * p.squaredNorm();
    Matrix3 I;
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c)   // the result is symmetric: compute the upper triangle
        I(r, c) = I(c, r) = rotational(r, c) - p[r] * g[c] - h[r] * p[c] + (r == c ? diagonal : 0.0);
    return {mass, g, I};
  }

  Matrix6 matrix() const {
    Matrix6 m;
    const Matrix3 H = skew(first_moment);
    m << mass * Matrix3::Identity(), -H, H, rotational;
    return m;
  }
};

}  // namespace csp
