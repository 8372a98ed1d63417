// State validity and certified motion checks: the arm's capsules and the tool's against the scene
// and against the arm itself, each pair against the clearance its obstacle class requires.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "csp/dynamics/collision_world.hpp"
#include "csp/io/scene.hpp"

namespace csp::planners {

// The tightest pair of one state: clearance = distance - required clearance of its class
// (the state is valid when clearance >= 0).
struct StateClearance {
  double clearance = 0.0;
  double distance = 0.0;
  // Names valid while the checker lives.
  std::string_view moving;          // arm or tool capsule
  std::string_view other;           // obstacle or (self pairs) arm capsule
  std::string_view obstacle_class;  // "self" for arm/tool pairs
  Vector3 on_moving = Vector3::Zero(), on_other = Vector3::Zero();
};

class ClearanceChecker {
 public:
  // A scene as load_scene validates it; its tool replaces the hand (capsules on the flange frame).
  // Keeps references to neither argument.
  ClearanceChecker(const Model& model, const Scene& scene);

  // Forward kinematics, then every pair whose broad-phase bound (bounding boxes) could beat the
  // tightest pair found so far, exactly.
  StateClearance check(const Vector7& q);
  bool is_valid(const Vector7& q) { return check(q).clearance >= 0.0; }

  // The naive baseline (and the test oracle of the broad phase): every pair exactly.
  StateClearance check_all_pairs(const Vector7& q);

  // The tightest pair of each obstacle class (classes(): the scene's, and "self") in one pass, for
  // clearance reports per class; a class without a pair (every obstacle exempt) reports +infinity.
  // broad_phase false: every pair exactly (the naive baseline).
  const std::vector<StateClearance>& check_by_class(const Vector7& q, bool broad_phase = true);
  const std::vector<std::string>& classes() const { return classes_; }

  // True only if no state on the straight joint-space segment q_a -> q_b is in collision
  // (conservative advancement, Schwarzer, Saha & Latombe 2005). Along the segment a point of link k
  // moves by at most sum_{j<=k} R_jk |dq_j| (R_jk from reach_from_joint); for a self pair (i, k),
  // i < k, the distance changes only through joints i+1..k. So if at the midpoint every pair's
  // clearance exceeds its bound over half the segment, the whole segment is free; otherwise bisect,
  // up to `max_depth` halvings (then: not certified).
  bool motion_is_free(const Vector7& q_a, const Vector7& q_b, int max_depth = 16);
  // The bound motion_is_free starts from: the least clearance any state of the segment can have
  // (every pair's clearance at the midpoint minus its reach over half the segment). >= 0: certified
  // free without bisection; the report's certified margin along a path.
  double certified_clearance(const Vector7& q_a, const Vector7& q_b);

  int num_pairs() const { return static_cast<int>(pairs_.size()); }

 private:
  struct Pair {
    int moving;
    int other;         // an obstacle of world_, or (self) another of its capsules
    bool self;
    int class_index;   // into classes_
    double required;   // clearance of the class
    Vector7 reach;     // per joint: how far a joint step can change the distance (0 for joints that cannot)
  };

  void place(const Vector7& q);
  Distance pair_distance(const Pair& pair) const;
  // Minimum over pairs of distance - required - reach . joint_step (joint_step = 0 for a state):
  // into best_[0], or per class into best_by_class_[class_index] when `best` is best_by_class_.
  void evaluate(const Vector7& joint_step, bool broad_phase, std::vector<StateClearance>& best);
  StateClearance evaluate(const Vector7& joint_step, bool broad_phase);

  Model model_;
  Data data_;
  CollisionWorld world_;   // the scene's: its capsules move, its obstacles stay
  std::vector<Pair> pairs_;
  std::vector<std::string> classes_;
  std::vector<StateClearance> best_, best_by_class_;
  std::vector<const Pair*> best_pair_;   // per slot of `best`, the pair found (no allocation per check)
  std::vector<Capsule> placed_;     // base frame, after place(): arm capsules, then the tool's
  std::vector<Aabb> placed_boxes_;
};

}  // namespace csp::planners
