// The collision world of the arm: the capsules that move with it (the arm's, then the tool's on the
// flange), the obstacles around it, which capsule meets which obstacle, and the capsules placed for
// a configuration. One world for the planner's clearance checks (planners' ClearanceChecker) and the
// emulator's contact with the scene (rt's SceneContact); each adds its own rules on top (the
// planner's self pairs and clearance classes, the contact's materials and tissue elements).
// Pure geometry: dynamics/io turns a scene file into a world (collision_world(const Scene&)).
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "csp/dynamics/geometry.hpp"

namespace csp {

using Shape = std::variant<Box, Capsule, Sphere, HalfSpace>;

// The shape's axis-aligned bounding box (the broad phase); none for a half-space, which is unbounded.
std::optional<Aabb> bounding_box(const Shape& shape);
// Signed distance of a capsule to the shape (geometry.hpp's, on_a on the capsule).
Distance distance(const Capsule& capsule, const Shape& shape);

struct CollisionObstacle {
  std::string name;
  Shape shape;                       // base frame
  std::vector<std::string> exempt;   // names of the moving capsules never checked against it
};

// A moving capsule and an obstacle that may touch: indices into CollisionWorld's lists.
struct CapsuleObstaclePair {
  int capsule = 0;
  int obstacle = 0;
};

class CollisionWorld {
 public:
  CollisionWorld(std::vector<FrameCapsule> capsules, std::vector<CollisionObstacle> obstacles);

  const std::vector<FrameCapsule>& capsules() const { return capsules_; }
  const std::vector<CollisionObstacle>& obstacles() const { return obstacles_; }
  // Each obstacle's bounding box, computed once (the obstacles do not move in the world's frame).
  const std::optional<Aabb>& obstacle_box(int obstacle) const { return obstacle_boxes_[obstacle]; }
  // Every capsule against every obstacle that does not exempt it, grouped by capsule in capsule
  // order, so that a user placing capsules lazily places each once.
  const std::vector<CapsuleObstaclePair>& pairs() const { return pairs_; }

  // A capsule in the base frame; `data` after forward_kinematics at the configuration.
  Capsule placed_capsule(const Data& data, int capsule) const;
  // Every capsule in the base frame with its bounding box (both resized to capsules().size()).
  void place(const Data& data, std::vector<Capsule>& placed, std::vector<Aabb>& boxes) const;

 private:
  std::vector<FrameCapsule> capsules_;
  std::vector<CollisionObstacle> obstacles_;
  std::vector<std::optional<Aabb>> obstacle_boxes_;
  std::vector<CapsuleObstaclePair> pairs_;
};

}  // namespace csp
