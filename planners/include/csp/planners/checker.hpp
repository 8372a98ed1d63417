// State validity and certified motion checks: the arm's capsules and the tool's against the scene
// and against the arm itself, each pair against the clearance its obstacle class requires.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "csp/dynamics/geometry.hpp"
#include "csp/planners/scene.hpp"

namespace csp::planners {

// The tightest pair of one state: clearance = distance - required clearance of its class
// (the state is valid when clearance >= 0).
struct StateClearance {
  double clearance = 0.0;
  double distance = 0.0;
  std::string_view moving;          // arm or tool capsule
  std::string_view other;           // obstacle or (self pairs) arm capsule
  std::string_view obstacle_class;  // "self" for arm/tool pairs
  Vector3 on_moving = Vector3::Zero(), on_other = Vector3::Zero();
};

class ClearanceChecker {
 public:
  // The scene's tool replaces the hand: capsules on the flange frame. Keeps references to neither.
  ClearanceChecker(const Model& model, const Scene& scene);

  // Forward kinematics, then every pair whose broad-phase bound (bounding boxes) could beat the
  // tightest pair found so far, exactly.
  StateClearance check(const Vector7& q);
  bool is_valid(const Vector7& q) { return check(q).clearance >= 0.0; }

  // The naive baseline (and the test oracle of the broad phase): every pair exactly.
  StateClearance check_all_pairs(const Vector7& q);

  // True only if no state on the straight joint-space segment q_a -> q_b is in collision
  // (conservative advancement, Schwarzer, Saha & Latombe 2005): a point on link k moves by at most
  // sum_{j<=k} R_jk |dq_j| along the segment (R_jk from reach_from_joint), so if the midpoint's
  // clearance of every pair exceeds the motion bound of both its capsules over half the segment,
  // the whole segment is free; otherwise bisect, up to `max_depth` halvings (then: not certified).
  bool motion_is_free(const Vector7& q_a, const Vector7& q_b, int max_depth = 16);

  int num_pairs() const { return static_cast<int>(pairs_.size()); }
  int num_moving() const { return static_cast<int>(moving_.size()); }
  // The base-frame capsules after the last check (arm capsules first, then the tool's).
  const std::vector<Capsule>& placed_capsules() const { return placed_; }

 private:
  struct Moving {
    std::string name;
    CapsuleFrame frame;
    Capsule local;
    Vector7 reach;   // R_j: bound on the distance of the capsule's points from joint j's axis
  };
  struct Static {
    std::string name;
    std::string obstacle_class;
    Shape shape;
    Aabb box;          // unused for half-spaces
    bool half_space;
  };
  struct Pair {
    int moving;
    int other;         // index into statics_, or into moving_ when self
    bool self;
    double required;   // clearance of the class
  };

  void place(const Vector7& q);
  Distance pair_distance(const Pair& pair) const;
  // Minimum over pairs of distance - required - (motion bound of each side); motion = 0 for a state.
  StateClearance evaluate(const std::vector<double>& motion, bool broad_phase);

  Model model_;
  Data data_;
  std::vector<Moving> moving_;
  std::vector<Static> statics_;
  std::vector<Pair> pairs_;
  std::vector<Capsule> placed_;
  std::vector<Aabb> placed_boxes_;
  std::vector<double> no_motion_, motion_;
};

}  // namespace csp::planners
