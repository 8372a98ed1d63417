// Collision geometry: convex primitives, their signed distances with closest points, and the
// Franka arm's published collision capsules placed by forward kinematics. Pure math, no allocation.
//
// Signed distance: the Euclidean distance between the two solids when they are apart (> 0), with
// closest points on the two surfaces. When they overlap, a negative number: minus the penetration
// depth along the reported direction, exact while the cores (segment, centre) are apart; when a
// capsule's segment itself enters a box, the deepest segment point's depth plus the radius. In
// every case |on_a - on_b| equals |distance|. Validity only needs the sign and the positive values.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "csp/dynamics/model.hpp"

namespace csp {

// A segment a-b swept by a sphere of `radius` (every arm link, every tool part, a limb).
struct Capsule {
  Vector3 a = Vector3::Zero();
  Vector3 b = Vector3::Zero();
  double radius = 0.0;
};

// The capsule moved by `by` (a moving obstacle's displacement taken off the capsule instead).
inline Capsule shifted(Capsule c, const Vector3& by) {
  c.a += by;
  c.b += by;
  return c;
}

struct Sphere {
  Vector3 center = Vector3::Zero();
  double radius = 0.0;
};

// An oriented box: pose of the box frame (origin at the centre, axes along the edges) and half sizes.
struct Box {
  Transform pose;
  Vector3 half_size = Vector3::Zero();
};

// The solid {x : normal . (x - point) <= 0}: `normal` (unit) points out of the solid, into free space.
struct HalfSpace {
  Vector3 point = Vector3::Zero();
  Vector3 normal = Vector3::UnitZ();
};

struct Distance {
  double distance = 0.0;            // signed, see above
  Vector3 on_a = Vector3::Zero();   // closest point on the first solid's surface
  Vector3 on_b = Vector3::Zero();   // closest point on the second solid's surface
};

// Closest points of segments p1-q1 and p2-q2 (Ericson 2005, Real-Time Collision Detection, sec. 5.1.9):
// s, t in [0, 1] with c1 = p1 + s (q1 - p1), c2 = p2 + t (q2 - p2). Degenerate segments (points) allowed.
struct SegmentClosestPoints {
  double s = 0.0, t = 0.0;
  Vector3 c1 = Vector3::Zero(), c2 = Vector3::Zero();
};
SegmentClosestPoints closest_points_segment_segment(const Vector3& p1, const Vector3& q1, const Vector3& p2,
                                                    const Vector3& q2);

// Closest point of segment a-b to point p, as the parameter t in [0, 1].
double closest_parameter_segment_point(const Vector3& a, const Vector3& b, const Vector3& p);

// Signed distance of a point to a box (negative inside: minus the depth to the nearest face).
double signed_distance_point_box(const Vector3& p, const Box& box);

Distance distance(const Capsule& a, const Capsule& b);
Distance distance(const Capsule& a, const Sphere& b);
Distance distance(const Capsule& a, const HalfSpace& b);
// Exact when apart: along the segment, the squared distance to the box is a convex piecewise
// quadratic whose pieces change only where the segment crosses one of the six face planes, so the
// minimum is found piece by piece in closed form (at most 7 pieces). When the segment enters the
// box, the signed distance of the segment points is convex and piecewise linear; its minimum is at
// a kink (two face distances equal) or an end, found by golden-section search to 1e-9 of the length.
Distance distance(const Capsule& a, const Box& b);

// Lower bound of the distance between two capsules' bounding spheres and an axis-aligned box of
// any solid (the broad phase): cheap, never larger than the true distance.
struct Aabb {
  Vector3 min = Vector3::Zero();
  Vector3 max = Vector3::Zero();
};
Aabb bounding_box(const Capsule& c);
Aabb bounding_box(const Sphere& s);
Aabb bounding_box(const Box& b);
double distance_lower_bound(const Aabb& a, const Aabb& b);   // 0 when they overlap

// ---- The Franka arm's collision capsules ----
//
// franka_description robots/common/franka_arm.xacro @032e7ee8 (Apache-2.0; identical in franka_ros
// franka_description/robots/common/franka_arm.xacro @b2a62ff6): per link, a cylinder of length L and
// radius r along one axis of the link frame, centred at c, capped by two spheres: the capsule with
// segment c +- (L/2) axis. The hand's two from franka_hand.xacro @4e8558dd. These are the robot's own
// self-collision model (Desk's `self_collision_avoidance_violation`), identical for Panda and FR3,
// hence one table here rather than a copy in each robot file (the robot files are generated from
// ../shared/data/franka_models.json, which does not carry them). Link frames are CSP's MDH frames,
// which are the URDF link frames (franka_description robots/fer/kinematics.yaml @1ddff9ba).
enum class CapsuleFrame { kBase = 0, kLink1, kLink2, kLink3, kLink4, kLink5, kLink6, kLink7, kFlange };

struct LinkCapsule {
  std::string_view name;
  CapsuleFrame frame;
  Capsule capsule;   // in `frame`
};

constexpr int kNumArmCapsules = 10;
constexpr int kNumHandCapsules = 2;
// Links 0..7 (links 5 and 7 have two each), in link order.
const std::array<LinkCapsule, kNumArmCapsules>& franka_arm_capsules();
// The Franka Hand, in the flange frame (the hand frame is the flange rotated -pi/4 about z, franka_robot.xacro).
const std::array<LinkCapsule, kNumHandCapsules>& franka_hand_capsules();

// Self-collision pairs of the arm, as indices into franka_arm_capsules(): the capsules of MoveIt's 9
// enabled link pairs (0,5) (0,6) (0,7) (1,5) (1,6) (1,7) (2,5) (2,7) (5,7) (moveit_resources
// panda_moveit_config panda_arm.xacro @445219e2 disables the other 19 of the 28 as adjacent or never
// in collision).
constexpr int kNumArmSelfPairs = 18;
const std::array<std::array<int, 2>, kNumArmSelfPairs>& franka_arm_self_pairs();

// A named capsule on one of the arm's frames: what the planner's clearance checker and the
// emulator's contact place by forward kinematics (the arm's, then the tool's on the flange).
struct FrameCapsule {
  std::string name;
  CapsuleFrame frame;
  Capsule local;   // in `frame`
};

// Pose of a capsule frame after forward_kinematics.
const Transform& capsule_frame_pose(const Data& data, CapsuleFrame frame);
// A capsule given in `frame_pose`'s frame, expressed in the base frame.
Capsule placed(const Capsule& capsule, const Transform& frame_pose);

// Upper bound on the distance of any point of a capsule on `frame` from the origin of joint j's
// frame (j = 1..7), whatever q: the triangle inequality along the MDH chain. Joint j's axis passes
// through that origin, so a joint step dq_j moves the point by at most this times |dq_j| (the reach
// in the certified motion check).
double reach_from_joint(const Model& model, int joint, CapsuleFrame frame, const Capsule& capsule);

}  // namespace csp
