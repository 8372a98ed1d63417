#include "csp/dynamics/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace csp {
namespace {

// A unit vector perpendicular to v (any), for touching solids whose closest points coincide.
Vector3 any_perpendicular(const Vector3& v) {
  const Vector3 other = std::abs(v.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  const Vector3 n = v.cross(other);
  return n.norm() > 0.0 ? n.normalized() : Vector3::UnitZ();
}

// Closest points c1 (on a solid of radius r1 around it) and c2 (radius r2): the distance and surface points.
Distance swept_spheres(const Vector3& c1, double r1, const Vector3& c2, double r2, const Vector3& fallback_axis) {
  const Vector3 d = c2 - c1;
  const double length = d.norm();
  const Vector3 u = length > 0.0 ? Vector3(d / length) : any_perpendicular(fallback_axis);
  return {length - r1 - r2, c1 + r1 * u, c2 - r2 * u};
}

}  // namespace

SegmentClosestPoints closest_points_segment_segment(const Vector3& p1, const Vector3& q1, const Vector3& p2,
                                                    const Vector3& q2) {
  // Ericson 2005, ClosestPtSegmentSegment (sec. 5.1.9).
  constexpr double kEpsilon = 1e-15;
  const Vector3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= kEpsilon && e <= kEpsilon) {
    // both points
  } else if (a <= kEpsilon) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEpsilon) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;   // >= 0; zero for parallel segments: any s, take 0
      s = denom > kEpsilon * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return {s, t, p1 + s * d1, p2 + t * d2};
}

double closest_parameter_segment_point(const Vector3& a, const Vector3& b, const Vector3& p) {
  const Vector3 d = b - a;
  const double length_squared = d.squaredNorm();
  return length_squared > 0.0 ? std::clamp((p - a).dot(d) / length_squared, 0.0, 1.0) : 0.0;
}

double signed_distance_point_box(const Vector3& p, const Box& box) {
  const Vector3 local = box.pose.rotation.transpose() * (p - box.pose.translation);
  const Vector3 excess = local.cwiseAbs() - box.half_size;   // > 0 on the axes where p is outside the slab
  return excess.cwiseMax(0.0).norm() + std::min(excess.maxCoeff(), 0.0);
}

Distance distance(const Capsule& a, const Capsule& b) {
  const SegmentClosestPoints c = closest_points_segment_segment(a.a, a.b, b.a, b.b);
  return swept_spheres(c.c1, a.radius, c.c2, b.radius, a.b - a.a);
}

Distance distance(const Capsule& a, const Sphere& b) {
  const double t = closest_parameter_segment_point(a.a, a.b, b.center);
  return swept_spheres(a.a + t * (a.b - a.a), a.radius, b.center, b.radius, a.b - a.a);
}

Distance distance(const Capsule& a, const HalfSpace& b) {
  const double height_a = b.normal.dot(a.a - b.point), height_b = b.normal.dot(a.b - b.point);
  const Vector3& lowest = height_a <= height_b ? a.a : a.b;
  const double height = std::min(height_a, height_b);
  return {height - a.radius, lowest - a.radius * b.normal, lowest - height * b.normal};
}

Distance distance(const Capsule& a, const Box& b) {
  const Matrix3& R = b.pose.rotation;
  const Vector3& h = b.half_size;
  // The segment in the box frame: p(t) = p0 + t d, t in [0, 1].
  const Vector3 p0 = R.transpose() * (a.a - b.pose.translation);
  const Vector3 d = R.transpose() * (a.b - a.a);

  // Breakpoints: where p(t) crosses a face plane x_i = +-h_i.
  std::array<double, 8> t_break{0.0, 1.0};
  int count = 2;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) continue;
    for (const double plane : {-h[i], h[i]}) {
      const double t = (plane - p0[i]) / d[i];
      if (t > 0.0 && t < 1.0) t_break[count++] = t;
    }
  }
  for (int i = 1; i < count; ++i)   // insertion sort of at most 8 values
    for (int k = i; k > 0 && t_break[k] < t_break[k - 1]; --k) std::swap(t_break[k], t_break[k - 1]);

  // On each piece the clamped axes are fixed, f^2(t) = sum over them of (p0_i + t d_i - s_i)^2.
  double best_t = 0.0, best_squared = std::numeric_limits<double>::infinity();
  for (int k = 0; k + 1 < count; ++k) {
    const double t0 = t_break[k], t1 = t_break[k + 1];
    const Vector3 middle = p0 + 0.5 * (t0 + t1) * d;
    double numerator = 0.0, denominator = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double face = middle[i] > h[i] ? h[i] : (middle[i] < -h[i] ? -h[i] : middle[i]);
      if (face == middle[i]) continue;   // inside this slab: no contribution
      numerator -= d[i] * (p0[i] - face);
      denominator += d[i] * d[i];
    }
    const double t = denominator > 0.0 ? std::clamp(numerator / denominator, t0, t1) : t0;
    const Vector3 p = p0 + t * d;
    const double squared = (p - p.cwiseMax(-h).cwiseMin(h)).squaredNorm();
    if (squared < best_squared) {
      best_squared = squared;
      best_t = t;
    }
  }

  if (best_squared > 0.0) {
    const Vector3 p = p0 + best_t * d;
    const Vector3 q = p.cwiseMax(-h).cwiseMin(h);
    const double gap = std::sqrt(best_squared);
    const Vector3 n = R * ((p - q) / gap);   // base frame, from the box toward the segment
    const Vector3 on_segment = a.a + best_t * (a.b - a.a);
    return {gap - a.radius, on_segment - a.radius * n, b.pose * q};
  }

  // The segment enters the box: minimise the (convex, piecewise linear) signed distance of p(t).
  auto depth = [&](double t) {
    const Vector3 p = p0 + t * d;
    return (p.cwiseAbs() - h).maxCoeff();
  };
  const double golden = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = 0.0, hi = 1.0;
  double x1 = hi - golden * (hi - lo), x2 = lo + golden * (hi - lo);
  double f1 = depth(x1), f2 = depth(x2);
  while (hi - lo > 1e-9) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - golden * (hi - lo);
      f1 = depth(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + golden * (hi - lo);
      f2 = depth(x2);
    }
  }
  double t = 0.5 * (lo + hi);
  for (const double end : {0.0, 1.0})
    if (depth(end) < depth(t)) t = end;
  const Vector3 p = p0 + t * d;
  int axis = 0;
  (p.cwiseAbs() - h).maxCoeff(&axis);
  const double inside = h[axis] - std::abs(p[axis]);   // >= 0: depth below the nearest face
  Vector3 face_normal = Vector3::Zero();
  face_normal[axis] = p[axis] >= 0.0 ? 1.0 : -1.0;
  const Vector3 n = R * face_normal;
  const Vector3 on_segment = a.a + t * (a.b - a.a);
  return {-inside - a.radius, on_segment - a.radius * n, on_segment + inside * n};
}

Aabb bounding_box(const Capsule& c) {
  const Vector3 r = Vector3::Constant(c.radius);
  return {c.a.cwiseMin(c.b) - r, c.a.cwiseMax(c.b) + r};
}

Aabb bounding_box(const Sphere& s) {
  const Vector3 r = Vector3::Constant(s.radius);
  return {s.center - r, s.center + r};
}

Aabb bounding_box(const Box& b) {
  const Vector3 extent = b.pose.rotation.cwiseAbs() * b.half_size;
  return {b.pose.translation - extent, b.pose.translation + extent};
}

double distance_lower_bound(const Aabb& a, const Aabb& b) {
  const Vector3 gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(0.0);
  return gap.norm();
}

// ---- Franka capsules ----
namespace {

enum class Axis { kX, kY, kZ };

// franka_description's <xacro:collision_capsule>: centre c, an axis of the (possibly rotated) link
// frame, cylinder length L, radius r; `rotation_z` is the rotation of the capsule's frame about the
// link frame's z axis.
Capsule xacro_capsule(const Vector3& center, Axis axis, double length, double radius, double rotation_z = 0.0) {
  const Vector3 half = 0.5 * length * (axis == Axis::kX ? Vector3::UnitX() : axis == Axis::kY ? Vector3::UnitY()
                                                                                              : Vector3::UnitZ());
  const Matrix3 R = Eigen::AngleAxisd(rotation_z, Vector3::UnitZ()).toRotationMatrix();
  return {R * (center - half), R * (center + half), radius};
}

constexpr double kQuarterPi = std::numbers::pi / 4.0;

}  // namespace

const std::array<LinkCapsule, kNumArmCapsules>& franka_arm_capsules() {
  using F = CapsuleFrame;
  static const std::array<LinkCapsule, kNumArmCapsules> capsules{{
      {"link0", F::kBase, xacro_capsule({-0.075, 0.0, 0.06}, Axis::kX, 0.03, 0.06)},
      {"link1", F::kLink1, xacro_capsule({0.0, 0.0, -0.1915}, Axis::kZ, 0.283, 0.06)},
      {"link2", F::kLink2, xacro_capsule({0.0, 0.0, 0.0}, Axis::kZ, 0.12, 0.06)},
      {"link3", F::kLink3, xacro_capsule({0.0, 0.0, -0.145}, Axis::kZ, 0.15, 0.06)},
      {"link4", F::kLink4, xacro_capsule({0.0, 0.0, 0.0}, Axis::kZ, 0.12, 0.06)},
      {"link5a", F::kLink5, xacro_capsule({0.0, 0.0, -0.26}, Axis::kZ, 0.10, 0.06)},
      {"link5b", F::kLink5, xacro_capsule({0.0, 0.08, -0.13}, Axis::kZ, 0.14, 0.025)},
      {"link6", F::kLink6, xacro_capsule({0.0, 0.0, -0.03}, Axis::kZ, 0.08, 0.05)},
      {"link7a", F::kLink7, xacro_capsule({0.0, 0.0, 0.01}, Axis::kZ, 0.14, 0.04, kQuarterPi)},
      {"link7b", F::kLink7, xacro_capsule({0.06, 0.0, 0.082}, Axis::kX, 0.01, 0.03, kQuarterPi)},
  }};
  return capsules;
}

const std::array<LinkCapsule, kNumHandCapsules>& franka_hand_capsules() {
  using F = CapsuleFrame;
  static const std::array<LinkCapsule, kNumHandCapsules> capsules{{
      {"hand_a", F::kFlange, xacro_capsule({0.0, 0.0, 0.04}, Axis::kY, 0.10, 0.04, -kQuarterPi)},
      {"hand_b", F::kFlange, xacro_capsule({0.0, 0.0, 0.10}, Axis::kY, 0.10, 0.02, -kQuarterPi)},
  }};
  return capsules;
}

const std::array<std::array<int, 2>, kNumArmSelfPairs>& franka_arm_self_pairs() {
  // Capsule indices: 0 link0, 1 link1, 2 link2, 3 link3, 4 link4, 5-6 link5, 7 link6, 8-9 link7.
  static const std::array<std::array<int, 2>, kNumArmSelfPairs> pairs{{
      {0, 5}, {0, 6}, {0, 7}, {0, 8}, {0, 9},   // link0 with links 5, 6, 7
      {1, 5}, {1, 6}, {1, 7}, {1, 8}, {1, 9},   // link1 with links 5, 6, 7
      {2, 5}, {2, 6}, {2, 8}, {2, 9},           // link2 with links 5, 7
      {5, 8}, {5, 9}, {6, 8}, {6, 9},           // link5 with link7
  }};
  return pairs;
}

const Transform& capsule_frame_pose(const Data& data, CapsuleFrame frame) {
  static const Transform identity;
  switch (frame) {
    case CapsuleFrame::kBase: return identity;
    case CapsuleFrame::kFlange: return data.O_T_F;
    default: return data.O_T_joint[static_cast<int>(frame) - 1];
  }
}

Capsule placed(const Capsule& capsule, const Transform& frame_pose) {
  return {frame_pose * capsule.a, frame_pose * capsule.b, capsule.radius};
}

double reach_from_joint(const Model& model, int joint, CapsuleFrame frame, const Capsule& capsule) {
  // From joint j's origin to frame k's origin: at most the sum of the fixed offsets of frames j+1..k.
  const int k = static_cast<int>(frame);   // 0 base, 1..7 links, 8 flange
  if (k < joint) return 0.0;                 // a frame before joint j does not move with it
  double chain = 0.0;
  for (int i = joint + 1; i <= std::min(k, kNumJoints); ++i) chain += model.joint(i - 1).origin.norm();
  if (frame == CapsuleFrame::kFlange) chain += model.parameters().link7_T_flange.translation.norm();
  return chain + std::max(capsule.a.norm(), capsule.b.norm()) + capsule.radius;
}

}  // namespace csp
