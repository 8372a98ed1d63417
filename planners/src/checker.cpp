#include "csp/planners/checker.hpp"

#include <algorithm>
#include <limits>

#include "csp/dynamics/algorithms.hpp"

namespace csp::planners {
namespace {

// The tool may touch links 6 and 7 (it is mounted on them); links 0-5 (capsules 0-6) it must not.
constexpr int kToolCheckedArmCapsules = 7;

}  // namespace

ClearanceChecker::ClearanceChecker(const Model& model, const Scene& scene)
    : model_(model), world_(collision_world(scene)) {
  for (const auto& [name, required] : scene.clearance) classes_.push_back(name);
  auto class_index = [&](const std::string& name) {
    return static_cast<int>(std::find(classes_.begin(), classes_.end(), name) - classes_.begin());
  };
  const std::vector<FrameCapsule>& moving = world_.capsules();

  // Against a fixed obstacle, every joint up to the capsule's link moves it; against an arm capsule
  // on frame i, only joints after i change the distance (the pair moves rigidly with joints 1..i).
  auto reach = [&](int capsule, int fixed_up_to_joint) {
    Vector7 r = Vector7::Zero();
    for (int j = fixed_up_to_joint + 1; j <= kNumJoints; ++j)
      r[j - 1] = reach_from_joint(model_, j, moving[capsule].frame, moving[capsule].local);
    return r;
  };
  for (const auto& [m, o] : world_.pairs()) {
    const std::string& obstacle_class = scene.obstacles[o].obstacle_class;
    pairs_.push_back({m, o, false, class_index(obstacle_class), scene.clearance.at(obstacle_class), reach(m, 0)});
  }
  const double self = scene.clearance.at("self");
  auto add_self = [&](int distal, int proximal) {
    pairs_.push_back({distal, proximal, true, class_index("self"), self, reach(distal, static_cast<int>(moving[proximal].frame))});
  };
  for (const auto& [a, b] : franka_arm_self_pairs()) add_self(b, a);
  for (int m = kNumArmCapsules; m < static_cast<int>(moving.size()); ++m)
    for (int a = 0; a < kToolCheckedArmCapsules; ++a) add_self(m, a);

  best_.resize(1);
  best_by_class_.resize(classes_.size());
  best_pair_.resize(classes_.size());
}

void ClearanceChecker::place(const Vector7& q) {
  forward_kinematics(model_, data_, q);
  world_.place(data_, placed_, placed_boxes_);
}

Distance ClearanceChecker::pair_distance(const Pair& pair) const {
  const Capsule& capsule = placed_[pair.moving];
  if (pair.self) return distance(capsule, placed_[pair.other]);
  return distance(capsule, world_.obstacles()[pair.other].shape);
}

void ClearanceChecker::evaluate(const Vector7& joint_step, bool broad_phase, std::vector<StateClearance>& best) {
  const bool by_class = &best == &best_by_class_;
  std::vector<const Pair*>& best_pair = best_pair_;
  std::fill(best_pair.begin(), best_pair.end(), nullptr);
  for (StateClearance& b : best) {
    b = StateClearance{};
    b.clearance = std::numeric_limits<double>::infinity();
  }
  for (const Pair& pair : pairs_) {
    const std::size_t slot = by_class ? static_cast<std::size_t>(pair.class_index) : 0;
    StateClearance& tightest = best[slot];
    const double margin = pair.required + pair.reach.dot(joint_step);
    if (broad_phase) {
      const std::optional<Aabb>& other = pair.self ? placed_boxes_[pair.other] : world_.obstacle_box(pair.other);
      if (other) {   // none: a half-space, checked exactly
        // The gap bounds the distance only while positive: overlapping boxes say nothing about the depth.
        const double gap = distance_lower_bound(placed_boxes_[pair.moving], *other);
        if (gap > 0.0 && gap - margin >= tightest.clearance) continue;
      }
    }
    const Distance d = pair_distance(pair);
    if (d.distance - margin < tightest.clearance) {
      tightest.clearance = d.distance - margin;
      tightest.distance = d.distance;
      tightest.on_moving = d.on_a;
      tightest.on_other = d.on_b;
      best_pair[slot] = &pair;
    }
  }
  for (std::size_t i = 0; i < best.size(); ++i) {
    const Pair* p = best_pair[i];
    if (!p) continue;
    const std::vector<FrameCapsule>& moving = world_.capsules();
    best[i].moving = moving[p->moving].name;
    best[i].other = p->self ? std::string_view(moving[p->other].name) : std::string_view(world_.obstacles()[p->other].name);
    best[i].obstacle_class = classes_[p->class_index];
  }
}

StateClearance ClearanceChecker::evaluate(const Vector7& joint_step, bool broad_phase) {
  evaluate(joint_step, broad_phase, best_);
  return best_[0];
}

const std::vector<StateClearance>& ClearanceChecker::check_by_class(const Vector7& q, bool broad_phase) {
  place(q);
  evaluate(Vector7::Zero(), broad_phase, best_by_class_);
  return best_by_class_;
}

StateClearance ClearanceChecker::check(const Vector7& q) {
  place(q);
  return evaluate(Vector7::Zero(), true);
}

StateClearance ClearanceChecker::check_all_pairs(const Vector7& q) {
  place(q);
  return evaluate(Vector7::Zero(), false);
}

double ClearanceChecker::certified_clearance(const Vector7& q_a, const Vector7& q_b) {
  place(0.5 * (q_a + q_b));
  return evaluate(0.5 * (q_b - q_a).cwiseAbs(), true).clearance;
}

bool ClearanceChecker::motion_is_free(const Vector7& q_a, const Vector7& q_b, int max_depth) {
  if (certified_clearance(q_a, q_b) >= 0.0) return true;   // leaves the midpoint placed
  if (max_depth == 0 || evaluate(Vector7::Zero(), true).clearance < 0.0) return false;   // not certified / collides
  const Vector7 middle = 0.5 * (q_a + q_b);
  return motion_is_free(q_a, middle, max_depth - 1) && motion_is_free(middle, q_b, max_depth - 1);
}

}  // namespace csp::planners
