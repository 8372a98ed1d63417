#include "csp/planners/checker.hpp"

#include <algorithm>
#include <limits>

#include "csp/dynamics/algorithms.hpp"

namespace csp::planners {
namespace {

// The tool may touch links 6 and 7 (it is mounted on them); links 0-5 (capsules 0-6) it must not.
constexpr int kToolCheckedArmCapsules = 7;

Aabb shape_box(const Shape& shape) {
  return std::visit(
      [](const auto& s) -> Aabb {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, HalfSpace>) return {};
        else return bounding_box(s);
      },
      shape);
}

}  // namespace

ClearanceChecker::ClearanceChecker(const Model& model, const Scene& scene) : model_(model) {
  auto add_moving = [&](std::string name, CapsuleFrame frame, const Capsule& local) {
    Vector7 reach;
    for (int j = 1; j <= kNumJoints; ++j) reach[j - 1] = reach_from_joint(model_, j, frame, local);
    moving_.push_back({std::move(name), frame, local, reach});
  };
  for (const auto& c : franka_arm_capsules()) add_moving(std::string(c.name), c.frame, c.capsule);
  for (const auto& c : scene.tool.capsules) add_moving(c.name, CapsuleFrame::kFlange, c.capsule);

  for (const auto& o : scene.obstacles)
    statics_.push_back({o.name, o.obstacle_class, o.shape, shape_box(o.shape), std::holds_alternative<HalfSpace>(o.shape)});

  for (int m = 0; m < num_moving(); ++m) {
    for (int s = 0; s < static_cast<int>(statics_.size()); ++s) {
      const auto& exempt = scene.obstacles[s].exempt;
      if (std::find(exempt.begin(), exempt.end(), moving_[m].name) != exempt.end()) continue;
      pairs_.push_back({m, s, false, scene.clearance.at(statics_[s].obstacle_class)});
    }
  }
  const double self = scene.clearance.at("self");
  for (const auto& [a, b] : franka_arm_self_pairs()) pairs_.push_back({b, a, true, self});
  for (int m = kNumArmCapsules; m < num_moving(); ++m)
    for (int a = 0; a < kToolCheckedArmCapsules; ++a) pairs_.push_back({m, a, true, self});

  placed_.resize(moving_.size());
  placed_boxes_.resize(moving_.size());
  no_motion_.assign(moving_.size(), 0.0);
  motion_.assign(moving_.size(), 0.0);
}

void ClearanceChecker::place(const Vector7& q) {
  forward_kinematics(model_, data_, q);
  for (std::size_t i = 0; i < moving_.size(); ++i) {
    placed_[i] = placed(moving_[i].local, capsule_frame_pose(data_, moving_[i].frame));
    placed_boxes_[i] = bounding_box(placed_[i]);
  }
}

Distance ClearanceChecker::pair_distance(const Pair& pair) const {
  const Capsule& capsule = placed_[pair.moving];
  if (pair.self) return distance(capsule, placed_[pair.other]);
  return std::visit([&](const auto& shape) { return distance(capsule, shape); }, statics_[pair.other].shape);
}

StateClearance ClearanceChecker::evaluate(const std::vector<double>& motion, bool broad_phase) {
  StateClearance best;
  best.clearance = std::numeric_limits<double>::infinity();
  const Pair* best_pair = nullptr;
  for (const Pair& pair : pairs_) {
    const double margin = pair.required + motion[pair.moving] + (pair.self ? motion[pair.other] : 0.0);
    if (broad_phase) {
      const bool half_space = !pair.self && statics_[pair.other].half_space;
      if (!half_space) {
        const Aabb& other = pair.self ? placed_boxes_[pair.other] : statics_[pair.other].box;
        if (distance_lower_bound(placed_boxes_[pair.moving], other) - margin >= best.clearance) continue;
      }
    }
    const Distance d = pair_distance(pair);
    if (d.distance - margin < best.clearance) {
      best.clearance = d.distance - margin;
      best.distance = d.distance;
      best.on_moving = d.on_a;
      best.on_other = d.on_b;
      best_pair = &pair;
    }
  }
  if (best_pair) {
    best.moving = moving_[best_pair->moving].name;
    best.other = best_pair->self ? std::string_view(moving_[best_pair->other].name)
                                 : std::string_view(statics_[best_pair->other].name);
    best.obstacle_class = best_pair->self ? std::string_view("self")
                                          : std::string_view(statics_[best_pair->other].obstacle_class);
  }
  return best;
}

StateClearance ClearanceChecker::check(const Vector7& q) {
  place(q);
  return evaluate(no_motion_, true);
}

StateClearance ClearanceChecker::check_all_pairs(const Vector7& q) {
  place(q);
  return evaluate(no_motion_, false);
}

bool ClearanceChecker::motion_is_free(const Vector7& q_a, const Vector7& q_b, int max_depth) {
  const Vector7 middle = 0.5 * (q_a + q_b);
  const Vector7 half_step = 0.5 * (q_b - q_a).cwiseAbs();
  place(middle);
  for (std::size_t i = 0; i < moving_.size(); ++i) motion_[i] = moving_[i].reach.dot(half_step);
  if (evaluate(motion_, true).clearance >= 0.0) return true;
  if (max_depth == 0 || evaluate(no_motion_, true).clearance < 0.0) return false;   // not certified / collides
  return motion_is_free(q_a, middle, max_depth - 1) && motion_is_free(middle, q_b, max_depth - 1);
}

}  // namespace csp::planners
