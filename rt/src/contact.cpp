#include "csp/rt/contact.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "csp/rt/emulator.hpp"   // kDeltaT

namespace csp::rt {
namespace {

// Below this penetration the normal's direction is round-off and the force negligible [m].
constexpr double kMinPenetration = 1e-12;
// How far ahead the substep rule looks [s]: the state it sees is the last substep's of the cycle
// before, up to a cycle before the end of the next one.
constexpr double kHorizon = 2.0 * kDeltaT;
// Pairs this close are watched for a contact within the horizon: 1 cm in 2 ms is 5 m/s, faster
// than any point of a Panda moves (its TCP's limit is 1.7 m/s, libfranka's kMaxTranslationalVelocity) [m].
constexpr double kLookAhead = 1e-2;

// The link a capsule's frame moves with (1..7), 0 for the base.
int link_of(CapsuleFrame frame) {
  return frame == CapsuleFrame::kFlange ? kNumJoints : static_cast<int>(frame);
}

Aabb grown(Aabb box, const Vector3& amplitude) {
  box.min -= amplitude.cwiseAbs();
  box.max += amplitude.cwiseAbs();
  return box;
}

// The obstacle's bounding box; half-spaces have none (always checked: one dot product).
std::optional<Aabb> shape_box(const Shape& shape) {
  return std::visit(
      [](const auto& s) -> std::optional<Aabb> {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, HalfSpace>) return std::nullopt;
        else return bounding_box(s);
      },
      shape);
}

Capsule shifted(Capsule c, const Vector3& by) {
  c.a += by;
  c.b += by;
  return c;
}

// Velocity of a point (base frame) of link `link` (1..7): the joints up to it, about their axes
// (Data::axis: linear-first motion vectors at the base origin).
Vector3 point_velocity(const Data& data, int link, const Vector7& dq, const Vector3& point) {
  Vector3 v = Vector3::Zero();
  for (int j = 0; j < link; ++j) v += (data.axis[j].head<3>() + data.axis[j].tail<3>().cross(point)) * dq[j];
  return v;
}

// The point's linear Jacobian (3 x 7, zero beyond `link`).
Eigen::Matrix<double, 3, kNumJoints> point_jacobian(const Data& data, int link, const Vector3& point) {
  Eigen::Matrix<double, 3, kNumJoints> J = Eigen::Matrix<double, 3, kNumJoints>::Zero();
  for (int j = 0; j < link; ++j) J.col(j) = data.axis[j].head<3>() + data.axis[j].tail<3>().cross(point);
  return J;
}

}  // namespace

SceneContact::SceneContact(std::shared_ptr<const Scene> scene, const ContactOptions& options)
    : scene_(std::move(scene)), options_(options) {
  if (!scene_) throw std::invalid_argument("contact: no scene");
  if (!(std::isfinite(options_.friction_velocity) && options_.friction_velocity > 0.0))
    throw std::invalid_argument("contact: friction_velocity: expected a positive speed [m/s]");
  if (options_.max_substeps < 1) throw std::invalid_argument("contact: max_substeps: expected at least 1");
  capsules_ = arm_and_tool_capsules(scene_->tool);
  for (const Obstacle& o : scene_->obstacles) {
    const Material* material = nullptr;
    if (!o.material.empty()) {
      const auto found = scene_->materials.find(o.material);
      if (found == scene_->materials.end())
        throw std::invalid_argument(scene_->path + ": obstacle `" + o.name + "`: no material `" + o.material + "`");
      if (const auto problem = material_problem(found->second))
        throw std::invalid_argument(scene_->path + ": material `" + o.material + "`: " + std::string(problem->key) +
                                    ": expected " + std::string(problem->expected));
      material = &found->second;
    }
    material_.push_back(material);
    const std::optional<Aabb> box = shape_box(o.shape);
    obstacle_box_.push_back(box ? grown(*box, o.motion.amplitude) : Aabb{});
  }
  for (int c = 0; c < static_cast<int>(capsules_.size()); ++c) {
    if (link_of(capsules_[c].frame) == 0) continue;   // the base capsule cannot move: nothing to push
    for (int o = 0; o < static_cast<int>(scene_->obstacles.size()); ++o) {
      const auto& exempt = scene_->obstacles[o].exempt;
      if (material_[o] && std::find(exempt.begin(), exempt.end(), capsules_[c].name) == exempt.end())
        pairs_.push_back({c, o});
    }
  }
}

ContactState SceneContact::initial_state() const {
  ContactState state;
  state.obstacle_normal_force.assign(scene_->obstacles.size(), 0.0);
  state.contacts.resize(pairs_.size());
  state.approaching.resize(pairs_.size());
  return state;
}

void SceneContact::require_clear(const Model& plant, Data& data, const Vector7& q) const {
  ContactState state = initial_state();
  evaluate(plant, data, 0.0, q, Vector7::Zero(), state);
  if (state.active_contacts == 0) return;
  const ContactPoint& c = *std::max_element(state.contacts.begin(), state.contacts.begin() + state.active_contacts,
                                            [](const auto& a, const auto& b) { return a.penetration < b.penetration; });
  std::ostringstream what;
  what << scene_->path << ": at the initial pose, capsule `" << capsules_[c.capsule].name << "` penetrates obstacle `"
       << scene_->obstacles[c.obstacle].name << "` by " << c.penetration * 1e3
       << " mm: start the arm clear of the scene's obstacles";
  throw std::invalid_argument(what.str());
}

void SceneContact::evaluate(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq,
                            ContactState& state) const {
  forward_kinematics(plant, data, q);
  std::fill(state.obstacle_normal_force.begin(), state.obstacle_normal_force.end(), 0.0);
  state.link_wrenches = kNoLinkWrenches;
  state.active_contacts = 0;
  state.approaching_contacts = 0;
  state.max_penetration = 0.0;
  Vector3 tool_force = Vector3::Zero(), tool_moment = Vector3::Zero();
  const Vector3 tcp = data.O_T_EE.translation;
  const int first_tool_capsule = kNumArmCapsules;

  int placed_index = -1;
  Capsule capsule;
  Aabb capsule_box;
  for (const Pair& pair : pairs_) {
    if (pair.capsule != placed_index) {   // pairs are grouped by capsule: place each once
      const FrameCapsule& c = capsules_[pair.capsule];
      capsule = placed(c.local, capsule_frame_pose(data, c.frame));
      capsule_box = bounding_box(capsule);
      placed_index = pair.capsule;
    }
    const Obstacle& obstacle = scene_->obstacles[pair.obstacle];
    if (!std::holds_alternative<HalfSpace>(obstacle.shape) &&
        distance_lower_bound(capsule_box, obstacle_box_[pair.obstacle]) > kLookAhead)
      continue;
    // A moving obstacle: the capsule moved back by the obstacle's displacement meets it at rest.
    const bool moves = obstacle.motion.frequency_hz > 0.0;
    const Vector3 displacement = moves ? obstacle.motion.displacement(t) : Vector3::Zero();
    const Capsule relative = moves ? shifted(capsule, -displacement) : capsule;
    const Distance d = std::visit([&](const auto& shape) { return distance(relative, shape); }, obstacle.shape);
    if (d.distance > kLookAhead || std::abs(d.distance) < kMinPenetration) continue;

    const bool touching = d.distance < 0.0;
    ContactPoint& contact = touching ? state.contacts[state.active_contacts] : state.approaching[state.approaching_contacts];
    contact.capsule = pair.capsule;
    contact.obstacle = pair.obstacle;
    contact.link = link_of(capsules_[pair.capsule].frame);
    contact.penetration = -d.distance;
    contact.normal = (d.on_a - d.on_b) / d.distance;   // on_a - on_b = distance x normal (geometry.hpp)
    contact.point = 0.5 * (d.on_a + d.on_b) + displacement;
    Vector3 velocity = point_velocity(data, contact.link, dq, contact.point);
    if (moves) velocity -= obstacle.motion.velocity(t);
    const double normal_velocity = contact.normal.dot(velocity);
    contact.penetration_rate = -normal_velocity;
    if (!touching) {   // apart: kept when it closes within the cycle
      contact.normal_force = 0.0;
      contact.force.setZero();
      if (contact.penetration + contact.penetration_rate * kHorizon > 0.0) ++state.approaching_contacts;
      continue;
    }
    ++state.active_contacts;
    const Material& m = *material_[pair.obstacle];
    contact.normal_force = hunt_crossley_force(m, contact.penetration, contact.penetration_rate);
    contact.force = contact.normal_force * contact.normal +
                    regularized_friction(m.friction, contact.normal_force, velocity - normal_velocity * contact.normal,
                                         options_.friction_velocity);

    state.max_penetration = std::max(state.max_penetration, contact.penetration);
    state.obstacle_normal_force[pair.obstacle] += contact.normal_force;
    const Transform& link = data.O_T_joint[contact.link - 1];
    const Vector3 force = link.rotation.transpose() * contact.force;
    const Vector3 arm = link.rotation.transpose() * (contact.point - link.translation);
    state.link_wrenches[contact.link - 1].head<3>() += force;
    state.link_wrenches[contact.link - 1].tail<3>() += arm.cross(force);
    if (pair.capsule >= first_tool_capsule) {
      tool_force += contact.force;
      tool_moment += (contact.point - tcp).cross(contact.force);
    }
  }
  state.O_F_tool << -tool_force, -tool_moment;
}

int SceneContact::required_substeps(const Model& plant, Data& data, const Vector7& q, const ContactState& state,
                                    int base) const {
  if (state.active_contacts == 0 && state.approaching_contacts == 0) return base;
  forward_kinematics(plant, data, q);
  crba(plant, data, q);
  const Eigen::LLT<Matrix7> mass(data.mass_matrix);
  double omega_squared = 0.0, damping_rate = 0.0;
  for (int i = 0; i < state.active_contacts + state.approaching_contacts; ++i) {
    const bool touching = i < state.active_contacts;
    const ContactPoint& c = touching ? state.contacts[i] : state.approaching[i - state.active_contacts];
    // The contact's inverse effective mass, bounded above for every direction by the trace of
    // J M^-1 J^T = |L^-1 J^T|_F^2 (M = L L^T).
    const Eigen::Matrix<double, 3, kNumJoints> J = point_jacobian(data, c.link, c.point);
    double inverse_mass = 0.0;
    for (int axis = 0; axis < 3; ++axis) inverse_mass += mass.matrixL().solve(Vector7(J.row(axis).transpose())).squaredNorm();
    const Material& m = *material_[c.obstacle];
    // Stiffness, damping and friction where the contact may be by the end of the cycle.
    const double depth = c.penetration + std::max(0.0, c.penetration_rate) * kHorizon;
    if (depth <= 0.0) continue;
    const double elastic = m.stiffness * std::pow(depth, m.exponent);
    const double normal_force = elastic * (1.0 + 1.5 * m.damping * std::max(0.0, c.penetration_rate));
    omega_squared += hunt_crossley_stiffness(m, depth) * inverse_mass;
    damping_rate += (1.5 * m.damping * elastic + m.friction * normal_force / options_.friction_velocity) * inverse_mass;
  }
  // Symplectic Euler is stable for h omega < 2 and an explicit damping for h gamma < 2: half of each.
  const double needed = kDeltaT * std::max(std::sqrt(omega_squared), damping_rate);
  return std::clamp(static_cast<int>(std::ceil(needed)), base, std::max(base, options_.max_substeps));
}

}  // namespace csp::rt
