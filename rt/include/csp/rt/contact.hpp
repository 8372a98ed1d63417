// The plant's contact with a scene (docs/contact.md): the arm's and the tool's capsules against
// the scene's obstacles that have a material, a Hunt-Crossley normal force and a regularised
// Coulomb friction at one point per capsule-obstacle pair, as wrenches on the links. The
// environment of the emulated arm: the real Panda has no such model, it meets the real world.
#pragma once

#include <memory>
#include <vector>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/scene.hpp"

namespace csp::rt {

// Scenario `contact:` options.
struct ContactOptions {
  // v_s of the regularised friction [m/s]: below the friction cone a contact creeps at a speed of
  // this order instead of sticking exactly; 1 mm/s is 1/20 of the slowest scan speed CSP ships.
  double friction_velocity = 1e-3;
  // Upper bound of the adaptive substeps per 1 ms cycle (docs/contact.md's rule).
  int max_substeps = 64;
};

// One capsule-obstacle contact.
struct ContactPoint {
  int capsule = 0;           // index into SceneContact::capsules()
  int obstacle = 0;          // index into Scene::obstacles
  int link = 7;              // the link it pushes on (1..7; the tool's: 7)
  Vector3 point = Vector3::Zero();    // base frame, midway between the two surfaces [m]
  Vector3 normal = Vector3::Zero();   // unit, from the obstacle toward the capsule
  double penetration = 0.0;           // [m]
  double penetration_rate = 0.0;      // [m/s], > 0 going in
  double normal_force = 0.0;          // [N]
  Vector3 force = Vector3::Zero();    // on the capsule: normal and friction, base frame [N]
};

// What the scene does to the arm in the last integration substep of a cycle (Emulator::contact()).
struct ContactState {
  // The wrench the tool exerts on the scene, with libfranka's sign for O_F_ext_hat_K (the robot on
  // its environment: minus what the scene applies on the tool): base-frame axes, moment about the
  // plant's TCP (its O_T_EE) [N, N m]. Comparable with O_F_ext_hat_K when K is at the TCP.
  Vector6 O_F_tool = Vector6::Zero();
  double max_penetration = 0.0;              // [m]
  int active_contacts = 0;                   // pairs in contact
  std::vector<double> obstacle_normal_force; // per scene obstacle, sum of its normal forces [N]
  std::vector<ContactPoint> contacts;        // the first active_contacts are this substep's
  // Pairs still apart that close within a cycle at their speed (penetration < 0: minus the gap;
  // no force): the substep rule's look-ahead.
  int approaching_contacts = 0;
  std::vector<ContactPoint> approaching;
  LinkWrenches link_wrenches = kNoLinkWrenches;   // on each link, link frame about its origin (f_ext)
  int substeps = 0;                          // integration substeps the cycle used
};

class SceneContact {
 public:
  // Throws std::invalid_argument for a material outside its ranges or options out of range.
  SceneContact(std::shared_ptr<const Scene> scene, const ContactOptions& options);

  const Scene& scene() const { return *scene_; }
  const ContactOptions& options() const { return options_; }
  const std::vector<FrameCapsule>& capsules() const { return capsules_; }
  ContactState initial_state() const;   // sized for this scene, nothing in contact

  // Throws std::invalid_argument naming the scene, the obstacle and the capsule when a capsule
  // penetrates an obstacle with a material at q (data: forward_kinematics workspace of `plant`).
  void require_clear(const Model& plant, Data& data, const Vector7& q) const;

  // Contacts and forces at time t [s] and state (q, dq) of `plant` (its F_T_EE the TCP): fills
  // `state` without allocating.
  void evaluate(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq,
                ContactState& state) const;

  // Substeps of 1 ms a cycle needs for the contacts in `state` (docs/contact.md): at least
  // `base`, at most options().max_substeps. Uses `data` for kinematics and the mass matrix at q.
  int required_substeps(const Model& plant, Data& data, const Vector7& q, const ContactState& state, int base) const;

 private:
  struct Pair {
    int capsule, obstacle;
  };
  std::shared_ptr<const Scene> scene_;
  ContactOptions options_;
  std::vector<FrameCapsule> capsules_;
  std::vector<const Material*> material_;   // per obstacle; null: no contact
  std::vector<Aabb> obstacle_box_;          // per obstacle at rest, grown by its motion's amplitude
  std::vector<Pair> pairs_;                 // capsules that can touch obstacles with a material
};

}  // namespace csp::rt
