// The plant's contact with a scene (docs/contact.md): the arm's and the tool's capsules against
// the scene's obstacles that have a material, a Hunt-Crossley normal force and a regularised
// Coulomb friction at one point per capsule-obstacle pair, as wrenches on the links. The
// environment of the emulated arm: the real Panda has no such model, it meets the real world.
#pragma once

#include <memory>
#include <string>
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

// What a tissue element does to the tool at one state of the arm.
struct ToolForce {
  Vector3 point = Vector3::Zero();   // where it acts, base frame [m] (on the tool: link 7)
  Vector3 force = Vector3::Zero();   // on the tool, base frame [N]
  double stiffness = 0.0;            // its largest d|F|/dx [N/m]: the substep rule's
};

// A tissue law the scene's rigid obstacles cannot express (rt/medical_plant.hpp: the bone under a
// burr, the trocar's ring in the abdominal wall). The contact engine evaluates it in every
// substep beside the obstacles, on the arm it has already placed, and applies its force to the
// tool like any contact's. One method, like OMPL's StateValidityChecker.
class ContactElement {
 public:
  virtual ~ContactElement() = default;
  // The force the tissue exerts on the tool at scenario time t [s], the plant placed in `data`
  // (forward_kinematics at q; its F_T_EE the TCP) and moving at dq. Called once per substep in
  // time order (an element may integrate its own state, e.g. the bone it removed), from inside the
  // 1 kHz loop: no allocation, no blocking.
  virtual ToolForce force(double t, const Data& data, const Vector7& dq) = 0;
};

// An element and the scene obstacle whose contact with the tool's working end (the tool capsule
// ending nearest the TCP) it replaces: the skull under the burr, the abdominal wall at the trocar.
// The arm's other capsules still meet that obstacle as a rigid shape.
struct TissueElement {
  std::shared_ptr<ContactElement> law;
  std::string obstacle;
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
  // The law's parts at the substep's start, for the implicit step (SceneContact::dissipate):
  Matrix3x7 jacobian = Matrix3x7::Zero();       // the point's, on its link
  Vector3 surface_velocity = Vector3::Zero();   // the obstacle's (breathing) [m/s]
  double elastic_force = 0.0;                   // k delta^n [N]
  double damping = 0.0;                         // (3/2) alpha k delta^n = -dF_n / d(separating speed) [N s/m]
  double friction_limit = 0.0;                  // mu F_n at the substep's start: the Coulomb force [N]
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
  std::vector<ToolForce> tissue;             // per tissue element, in the order given to SceneContact
  int substeps = 0;                          // integration substeps the cycle used
  int newton_iterations = 0;                 // Newton steps the last substep's implicit step took (dissipate)
};

class SceneContact {
 public:
  // Throws std::invalid_argument for a material outside its ranges, options out of range, or a
  // tissue element naming no obstacle of the scene.
  SceneContact(std::shared_ptr<const Scene> scene, const ContactOptions& options,
               std::vector<TissueElement> tissue = {});

  const Scene& scene() const { return *scene_; }
  const ContactOptions& options() const { return options_; }
  const std::vector<FrameCapsule>& capsules() const { return world_.capsules(); }
  ContactState initial_state() const;   // sized for this scene, nothing in contact

  // Throws std::invalid_argument naming the scene, the obstacle and the capsule when a capsule
  // penetrates an obstacle with a material at q (data: forward_kinematics workspace of `plant`).
  void require_clear(const Model& plant, Data& data, const Vector7& q) const;

  // One substep's contacts at time t [s] and state (q, dq) of `plant` (its F_T_EE the TCP), without
  // allocating: the geometry, each contact's law at (q, dq), and the explicit part of the forces in
  // `state` (the normal law's elastic force k delta^n and the tissue elements' forces, as link
  // wrenches and O_F_tool). The dissipative part (Hunt-Crossley damping, friction) acts on the new
  // velocity: dissipate() adds it. Leaves `data` at q. Calls each tissue element once.
  void evaluate(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq, ContactState& state);

  // The implicit step of the contacts' dissipative forces (docs/contact.md). v_free is the joint
  // velocity a substep of length h reaches under every other force (the elastic contact forces
  // included), M the plant's mass matrix with armature; returns the velocity v at the substep's
  // end, backward Euler on the damping and the friction: v minimises the strictly convex
  //     1/2 (v - v_free)^T M (v - v_free) + h sum_c [psi_c(u_c) + mu F_n,c sqrt(|w_c|^2 + v_s^2)]
  // (u_c, w_c: the contact point's separating speed and slip at v; psi_c the damping's potential),
  // by Newton's method with a backtracking line search from v_start (the substep's start velocity:
  // at a steady stick or creep the answer). Then adds the dissipative forces at v to `state`
  // (add_dissipative_forces). `data`: evaluate's kinematics.
  Vector7 dissipate(const Data& data, const Matrix7& mass_matrix, const Vector7& v_start, const Vector7& v_free,
                    double h, ContactState& state) const;
  // Adds the damping and friction at joint velocity v to the contacts in `state`: each contact's
  // normal force and force, the link wrenches, O_F_tool, the obstacles' normal forces.
  void add_dissipative_forces(const Data& data, const Vector7& v, ContactState& state) const;

  // Substeps of 1 ms a cycle needs for the contacts in `state` (docs/contact.md): at least
  // `base`, at most options().max_substeps: the contacts' Jacobians are the state's (of its
  // substep), `data` holds the mass matrix at q and, with tissue, the kinematics.
  int required_substeps(const Model& plant, Data& data, const Vector7& q, const ContactState& state, int base) const;

 private:
  void evaluate_obstacles(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq,
                          ContactState& state) const;
  void add_force(const Data& data, int link, const Vector3& point, const Vector3& force, bool on_tool,
                 ContactState& state) const;

  std::shared_ptr<const Scene> scene_;
  ContactOptions options_;
  std::vector<TissueElement> tissue_;
  CollisionWorld world_;                    // the scene's capsules and obstacles
  std::vector<const Material*> material_;   // per obstacle; null: no contact
  std::vector<Aabb> obstacle_box_;          // per obstacle at rest, grown by its motion's amplitude
  std::vector<CapsuleObstaclePair> pairs_;  // capsules that can touch obstacles with a material
};

}  // namespace csp::rt
