#include "csp/dynamics/collision_world.hpp"

#include <algorithm>
#include <type_traits>

namespace csp {

std::optional<Aabb> bounding_box(const Shape& shape) {
  return std::visit(
      [](const auto& s) -> std::optional<Aabb> {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, HalfSpace>) return std::nullopt;
        else return bounding_box(s);
      },
      shape);
}

Distance distance(const Capsule& capsule, const Shape& shape) {
  return std::visit([&](const auto& s) { return distance(capsule, s); }, shape);
}

CollisionWorld::CollisionWorld(std::vector<FrameCapsule> capsules, std::vector<CollisionObstacle> obstacles)
    : capsules_(std::move(capsules)), obstacles_(std::move(obstacles)) {
  for (const CollisionObstacle& o : obstacles_) obstacle_boxes_.push_back(bounding_box(o.shape));
  for (int c = 0; c < static_cast<int>(capsules_.size()); ++c)
    for (int o = 0; o < static_cast<int>(obstacles_.size()); ++o) {
      const std::vector<std::string>& exempt = obstacles_[o].exempt;
      if (std::find(exempt.begin(), exempt.end(), capsules_[c].name) == exempt.end()) pairs_.push_back({c, o});
    }
}

Capsule CollisionWorld::placed_capsule(const Data& data, int capsule) const {
  const FrameCapsule& c = capsules_[capsule];
  return placed(c.local, capsule_frame_pose(data, c.frame));
}

void CollisionWorld::place(const Data& data, std::vector<Capsule>& placed, std::vector<Aabb>& boxes) const {
  placed.resize(capsules_.size());
  boxes.resize(capsules_.size());
  for (std::size_t i = 0; i < capsules_.size(); ++i) {
    placed[i] = placed_capsule(data, static_cast<int>(i));
    boxes[i] = bounding_box(placed[i]);
  }
}

}  // namespace csp
