#include "csp/planners/checker.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>

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
  for (const auto& c : franka_arm_capsules()) moving_.push_back({std::string(c.name), c.frame, c.capsule});
  for (const auto& c : scene.tool.capsules) moving_.push_back({c.name, CapsuleFrame::kFlange, c.capsule});

  for (const auto& o : scene.obstacles)
    statics_.push_back({o.name, o.obstacle_class, o.shape, shape_box(o.shape), std::holds_alternative<HalfSpace>(o.shape)});

  // Against a fixed obstacle, every joint up to the capsule's link moves it; against an arm capsule
  // on frame i, only joints after i change the distance (the pair moves rigidly with joints 1..i).
  auto reach = [&](int moving, int fixed_up_to_joint) {
    Vector7 r = Vector7::Zero();
    for (int j = fixed_up_to_joint + 1; j <= kNumJoints; ++j)
      r[j - 1] = reach_from_joint(model_, j, moving_[moving].frame, moving_[moving].local);
    return r;
  };
  for (int m = 0; m < static_cast<int>(moving_.size()); ++m) {
    for (int s = 0; s < static_cast<int>(statics_.size()); ++s) {
      const auto& exempt = scene.obstacles[s].exempt;
      if (std::find(exempt.begin(), exempt.end(), moving_[m].name) != exempt.end()) continue;
      pairs_.push_back({m, s, false, scene.clearance.at(statics_[s].obstacle_class), reach(m, 0)});
    }
  }
  const double self = scene.clearance.at("self");
  auto add_self = [&](int distal, int proximal) {
    pairs_.push_back({distal, proximal, true, self, reach(distal, static_cast<int>(moving_[proximal].frame))});
  };
  for (const auto& [a, b] : franka_arm_self_pairs()) add_self(b, a);
  for (int m = kNumArmCapsules; m < static_cast<int>(moving_.size()); ++m)
    for (int a = 0; a < kToolCheckedArmCapsules; ++a) add_self(m, a);

  placed_.resize(moving_.size());
  placed_boxes_.resize(moving_.size());
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

StateClearance ClearanceChecker::evaluate(const Vector7& joint_step, bool broad_phase) {
  StateClearance best;
  best.clearance = std::numeric_limits<double>::infinity();
  const Pair* best_pair = nullptr;
  for (const Pair& pair : pairs_) {
    const double margin = pair.required + pair.reach.dot(joint_step);
    if (broad_phase) {
      const bool half_space = !pair.self && statics_[pair.other].half_space;
      if (!half_space) {
        const Aabb& other = pair.self ? placed_boxes_[pair.other] : statics_[pair.other].box;
        // The gap bounds the distance only while positive: overlapping boxes say nothing about the depth.
        const double gap = distance_lower_bound(placed_boxes_[pair.moving], other);
        if (gap > 0.0 && gap - margin >= best.clearance) continue;
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
  return evaluate(Vector7::Zero(), true);
}

StateClearance ClearanceChecker::check_all_pairs(const Vector7& q) {
  place(q);
  return evaluate(Vector7::Zero(), false);
}

bool ClearanceChecker::motion_is_free(const Vector7& q_a, const Vector7& q_b, int max_depth) {
  const Vector7 middle = 0.5 * (q_a + q_b);
  const Vector7 half_step = 0.5 * (q_b - q_a).cwiseAbs();
  place(middle);
  if (evaluate(half_step, true).clearance >= 0.0) return true;
  if (max_depth == 0 || evaluate(Vector7::Zero(), true).clearance < 0.0) return false;   // not certified / collides
  return motion_is_free(q_a, middle, max_depth - 1) && motion_is_free(middle, q_b, max_depth - 1);
}

}  // namespace csp::planners
