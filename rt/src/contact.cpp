#include "csp/rt/contact.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
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
// Newton steps of the implicit dissipation step before it takes its iterate (a safety net: pressing
// and sliding take 0 to 4, the tests' impacts on stiff materials up to 11).
constexpr int kMaxDissipationIterations = 20;

// The link a capsule's frame moves with (1..7), 0 for the base.
int link_of(CapsuleFrame frame) {
  return frame == CapsuleFrame::kFlange ? kNumJoints : static_cast<int>(frame);
}

Aabb grown(Aabb box, const Vector3& amplitude) {
  box.min -= amplitude.cwiseAbs();
  box.max += amplitude.cwiseAbs();
  return box;
}

// A contact's motion relative to the surface at joint velocity v: the separating speed u (along
// the normal) and the slip w (in the tangent plane).
struct RelativeMotion {
  double u;
  Vector3 w;
};
RelativeMotion relative_motion(const ContactPoint& c, const Vector7& v) {
  const Vector3 r = c.jacobian * v - c.surface_velocity;
  const double u = c.normal.dot(r);
  return {u, r - u * c.normal};
}

// psi'(u) of the Hunt-Crossley damping at separating speed u: the normal force is
// F_n = e - c u >= 0 (e = k delta^n, c = (3/2) alpha e), so its velocity-dependent part is
// -min(c u, e): c u while the contact presses, e (all of the elastic force) once it would pull.
double damping_slope_force(double elastic, double damping, double u) { return std::min(damping * u, elastic); }

// psi(u), the potential whose derivative that is (convex: c u^2 / 2, then linear).
double damping_potential(double elastic, double damping, double u) {
  if (damping * u <= elastic) return 0.5 * damping * u * u;
  return elastic * u - 0.5 * elastic * elastic / damping;
}

// The scene, checked before the collision world is built from it.
std::shared_ptr<const Scene> required(std::shared_ptr<const Scene> scene) {
  if (!scene) throw std::invalid_argument("contact: no scene");
  return scene;
}

}  // namespace

SceneContact::SceneContact(std::shared_ptr<const Scene> scene, const ContactOptions& options,
                           std::vector<TissueElement> tissue)
    : scene_(required(std::move(scene))), options_(options), tissue_(std::move(tissue)), world_(collision_world(*scene_)) {
  if (!(std::isfinite(options_.friction_velocity) && options_.friction_velocity > 0.0))
    throw std::invalid_argument("contact: friction_velocity: expected a positive speed [m/s]");
  if (options_.max_substeps < 1) throw std::invalid_argument("contact: max_substeps: expected at least 1");
  for (std::size_t i = 0; i < scene_->obstacles.size(); ++i) {
    const Obstacle& o = scene_->obstacles[i];
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
    // Half-spaces have no box (always checked: one dot product).
    const std::optional<Aabb>& box = world_.obstacle_box(static_cast<int>(i));
    obstacle_box_.push_back(box ? grown(*box, o.motion.amplitude) : Aabb{});
  }
  // The pairs a tissue element replaces: its obstacle against the tool's working end (after the
  // arm's capsules in capsules()).
  std::vector<CapsuleObstaclePair> replaced;
  const int tip = tool_tip_capsule(scene_->tool);
  for (const TissueElement& element : tissue_) {
    if (!element.law) throw std::invalid_argument("contact: a tissue element without a law");
    const int obstacle = scene_->obstacle_index(element.obstacle);
    if (obstacle < 0)
      throw std::invalid_argument(scene_->path + ": no obstacle `" + element.obstacle + "` for a tissue element");
    if (tip < 0) throw std::invalid_argument(scene_->path + ": a tissue element needs a tool with capsules (its working end)");
    replaced.push_back({kNumArmCapsules + tip, obstacle});
  }
  // The world's pairs (exempt capsules left out) that can push: an obstacle with a material, a
  // capsule that moves (the base capsule cannot: nothing to push), not replaced by a tissue element.
  for (const CapsuleObstaclePair& pair : world_.pairs()) {
    const bool is_replaced = std::any_of(replaced.begin(), replaced.end(), [&](const CapsuleObstaclePair& r) {
      return r.capsule == pair.capsule && r.obstacle == pair.obstacle;
    });
    if (link_of(capsules()[pair.capsule].frame) != 0 && material_[pair.obstacle] && !is_replaced) pairs_.push_back(pair);
  }
}

ContactState SceneContact::initial_state() const {
  ContactState state;
  state.obstacle_normal_force.assign(scene_->obstacles.size(), 0.0);
  state.contacts.resize(pairs_.size());
  state.approaching.resize(pairs_.size());
  state.tissue.resize(tissue_.size());
  return state;
}

void SceneContact::require_clear(const Model& plant, Data& data, const Vector7& q) const {
  ContactState state = initial_state();
  evaluate_obstacles(plant, data, 0.0, q, Vector7::Zero(), state);
  if (state.active_contacts == 0) return;
  const ContactPoint& c = *std::max_element(state.contacts.begin(), state.contacts.begin() + state.active_contacts,
                                            [](const auto& a, const auto& b) { return a.penetration < b.penetration; });
  std::ostringstream what;
  what << scene_->path << ": at the initial pose, capsule `" << capsules()[c.capsule].name << "` penetrates obstacle `"
       << scene_->obstacles[c.obstacle].name << "` by " << c.penetration * 1e3
       << " mm: start the arm clear of the scene's obstacles";
  throw std::invalid_argument(what.str());
}

void SceneContact::evaluate(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq,
                            ContactState& state) {
  evaluate_obstacles(plant, data, t, q, dq, state);
  for (std::size_t i = 0; i < tissue_.size(); ++i) {
    state.tissue[i] = tissue_[i].law->force(t, data, dq);
    add_force(data, kNumJoints, state.tissue[i].point, state.tissue[i].force, true, state);
  }
}

void SceneContact::evaluate_obstacles(const Model& plant, Data& data, double t, const Vector7& q, const Vector7& dq,
                                      ContactState& state) const {
  forward_kinematics(plant, data, q);
  std::fill(state.obstacle_normal_force.begin(), state.obstacle_normal_force.end(), 0.0);
  state.link_wrenches = kNoLinkWrenches;
  state.O_F_tool.setZero();
  state.active_contacts = 0;
  state.approaching_contacts = 0;
  state.max_penetration = 0.0;

  int placed_index = -1;
  Capsule capsule;
  Aabb capsule_box;
  for (const CapsuleObstaclePair& pair : pairs_) {
    if (pair.capsule != placed_index) {   // pairs are grouped by capsule: place each once
      capsule = world_.placed_capsule(data, pair.capsule);
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
    const Distance d = distance(relative, obstacle.shape);
    if (d.distance > kLookAhead || std::abs(d.distance) < kMinPenetration) continue;

    const bool touching = d.distance < 0.0;
    ContactPoint& contact = touching ? state.contacts[state.active_contacts] : state.approaching[state.approaching_contacts];
    contact.capsule = pair.capsule;
    contact.obstacle = pair.obstacle;
    contact.link = link_of(capsules()[pair.capsule].frame);
    contact.penetration = -d.distance;
    contact.normal = (d.on_a - d.on_b) / d.distance;   // on_a - on_b = distance x normal (geometry.hpp)
    contact.point = 0.5 * (d.on_a + d.on_b) + displacement;
    contact.jacobian = point_jacobian(data, contact.link, contact.point);
    contact.surface_velocity = moves ? obstacle.motion.velocity(t) : Vector3::Zero();
    const Vector3 velocity = contact.jacobian * dq - contact.surface_velocity;
    contact.penetration_rate = -contact.normal.dot(velocity);
    if (!touching) {   // apart: kept when it closes within the cycle
      contact.normal_force = 0.0;
      contact.force.setZero();
      if (contact.penetration + contact.penetration_rate * kHorizon > 0.0) ++state.approaching_contacts;
      continue;
    }
    ++state.active_contacts;
    // The law at (q, dq): its elastic part is applied now, its damping and friction (the friction
    // bounded by the normal force at dq) on the new velocity (dissipate).
    const Material& m = *material_[pair.obstacle];
    contact.elastic_force = hunt_crossley_force(m, contact.penetration, 0.0);
    contact.damping = 1.5 * m.damping * contact.elastic_force;
    contact.friction_limit = m.friction * hunt_crossley_force(m, contact.penetration, contact.penetration_rate);
    contact.normal_force = contact.elastic_force;
    contact.force = contact.elastic_force * contact.normal;
    state.max_penetration = std::max(state.max_penetration, contact.penetration);
    state.obstacle_normal_force[pair.obstacle] += contact.normal_force;
    add_force(data, contact.link, contact.point, contact.force, pair.capsule >= kNumArmCapsules, state);
  }
}

// A force on link `link` at `point` (base frame): the link-frame wrench about its origin, and, on
// the tool, O_F_tool (the tool on the scene: minus it, about the TCP).
void SceneContact::add_force(const Data& data, int link, const Vector3& point, const Vector3& force, bool on_tool,
                             ContactState& state) const {
  const Transform& frame = data.O_T_joint[link - 1];
  const Vector3 f = frame.rotation.transpose() * force;
  const Vector3 arm = frame.rotation.transpose() * (point - frame.translation);
  state.link_wrenches[link - 1].head<3>() += f;
  state.link_wrenches[link - 1].tail<3>() += arm.cross(f);
  if (on_tool) {
    state.O_F_tool.head<3>() -= force;
    state.O_F_tool.tail<3>() -= (point - data.O_T_EE.translation).cross(force);
  }
}

Vector7 SceneContact::dissipate(const Data& data, const Matrix7& M, const Vector7& v_start, const Vector7& v_free,
                                double h, ContactState& state) const {
  const double v_s = options_.friction_velocity;
  const std::span<const ContactPoint> contacts(state.contacts.data(), static_cast<std::size_t>(state.active_contacts));
  // Phi(v), contact by contact in the contact's separating speed u and slip w.
  auto objective = [&](const Vector7& v) {
    double phi = 0.5 * (v - v_free).dot(M * (v - v_free));
    for (const ContactPoint& c : contacts) {
      const auto [u, w] = relative_motion(c, v);
      phi += h * (damping_potential(c.elastic_force, c.damping, u) + c.friction_limit * std::sqrt(w.squaredNorm() + v_s * v_s));
    }
    return phi;
  };
  state.newton_iterations = 0;
  if (contacts.empty()) return v_free;
  // The gradient's scale: the momentum the step changes and the impulses the contacts can give.
  double scale = (M * v_free).cwiseAbs().maxCoeff();
  for (const ContactPoint& c : contacts)
    scale += h * (c.elastic_force + c.friction_limit) * c.jacobian.cwiseAbs().maxCoeff();
  Vector7 v = v_start;
  std::optional<double> phi;   // Phi(v), once a line search needs it
  for (int iteration = 0; iteration < kMaxDissipationIterations; ++iteration) {
    Vector7 gradient = M * (v - v_free);
    Matrix7 hessian = M;
    for (const ContactPoint& c : contacts) {
      const auto [u, w] = relative_motion(c, v);
      const double rho = std::sqrt(w.squaredNorm() + v_s * v_s);
      const Vector3 slope = damping_slope_force(c.elastic_force, c.damping, u) * c.normal + c.friction_limit / rho * w;
      Matrix3 curvature = (c.friction_limit / rho) *
                          (Matrix3::Identity() - c.normal * c.normal.transpose() - w * w.transpose() / (rho * rho));
      if (c.damping * u < c.elastic_force) curvature += c.damping * c.normal * c.normal.transpose();
      gradient += h * c.jacobian.transpose() * slope;
      hessian += h * c.jacobian.transpose() * curvature * c.jacobian;
    }
    // Stationary to round-off: the backward-Euler equation holds (at a steady stick or creep
    // v_start is already the answer).
    if (gradient.cwiseAbs().maxCoeff() <= 1e-12 * scale) break;
    const Vector7 step = -hessian.llt().solve(gradient);
    const double decrease = -gradient.dot(step);   // the Newton decrement squared: Phi's predicted fall x 2
    if (!phi) phi = objective(v);
    ++state.newton_iterations;
    // A fall Phi's round-off could not see: Newton's quadratic convergence has reached the minimiser
    // to round-off; the full step is the last.
    if (decrease <= 1e-14 * std::abs(*phi)) {
      v += step;
      break;
    }
    // Backtracking (Armijo): Phi is convex, so a short enough Newton step always decreases it.
    double length = 1.0, phi_next = objective(v + step);
    while (phi_next > *phi - 1e-4 * length * decrease && length >= 1e-10) {
      length *= 0.5;
      phi_next = objective(v + length * step);
    }
    if (length < 1e-10) break;   // no decrease left above round-off: v is the minimiser
    v += length * step;
    phi = phi_next;
  }
  add_dissipative_forces(data, v, state);
  return v;
}

void SceneContact::add_dissipative_forces(const Data& data, const Vector7& v, ContactState& state) const {
  const double v_s = options_.friction_velocity;
  for (int i = 0; i < state.active_contacts; ++i) {
    ContactPoint& c = state.contacts[i];
    const auto [u, w] = relative_motion(c, v);
    const double damping_force = -damping_slope_force(c.elastic_force, c.damping, u);   // along the normal
    const Vector3 friction = regularized_friction(1.0, c.friction_limit, w, v_s);
    const Vector3 force = damping_force * c.normal + friction;
    c.normal_force += damping_force;
    c.force += force;
    state.obstacle_normal_force[c.obstacle] += damping_force;
    add_force(data, c.link, c.point, force, c.capsule >= kNumArmCapsules, state);
  }
}

int SceneContact::required_substeps(const Model& plant, Data& data, const Vector7& q, const ContactState& state,
                                    int base) const {
  const bool tissue_stiff = std::any_of(state.tissue.begin(), state.tissue.end(),
                                        [](const ToolForce& f) { return f.stiffness > 0.0; });
  if (state.active_contacts == 0 && state.approaching_contacts == 0 && !tissue_stiff) return base;
  crba(plant, data, q);
  const Eigen::LLT<Matrix7> mass(data.mass_matrix);
  // The point's inverse effective mass, bounded above for every direction by the trace of
  // J M^-1 J^T = |L^-1 J^T|_F^2 (M = L L^T).
  auto inverse_mass = [&](const Matrix3x7& J) {
    double sum = 0.0;
    for (int axis = 0; axis < 3; ++axis) sum += mass.matrixL().solve(Vector7(J.row(axis).transpose())).squaredNorm();
    return sum;
  };
  double omega_squared = 0.0;
  for (int i = 0; i < state.active_contacts + state.approaching_contacts; ++i) {
    const bool touching = i < state.active_contacts;
    const ContactPoint& c = touching ? state.contacts[i] : state.approaching[i - state.active_contacts];
    // The stiffness where the contact may be by the end of the cycle.
    const double depth = c.penetration + std::max(0.0, c.penetration_rate) * kHorizon;
    if (depth <= 0.0) continue;
    omega_squared += hunt_crossley_stiffness(*material_[c.obstacle], depth) * inverse_mass(c.jacobian);
  }
  if (tissue_stiff) forward_kinematics(plant, data, q);   // the tissue points' Jacobians (the contacts keep theirs)
  for (const ToolForce& f : state.tissue)
    if (f.stiffness > 0.0) omega_squared += f.stiffness * inverse_mass(point_jacobian(data, kNumJoints, f.point));
  // Symplectic Euler is stable for h omega < 2: half of it (the damping and the friction are
  // implicit, dissipate(), and stable at any step).
  const double needed = kDeltaT * std::sqrt(omega_squared);
  return std::clamp(static_cast<int>(std::ceil(needed)), base, std::max(base, options_.max_substeps));
}

}  // namespace csp::rt
