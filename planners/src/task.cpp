#include "csp/planners/task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/geometry.hpp"

namespace csp::planners {
namespace {

// The rcm sweep spans +-2/3 of max_pivot in the y-z plane (along the body), at the middle of the
// insertion range: the planner keeps room inside the pivot range on the way.
constexpr double kSweepFraction = 2.0 / 3.0;
// How far the task's contact point may lie from the patient solid it touches.
constexpr double kContactTolerance = 0.02;
// Scan start and end must lie on the skin solid this closely (the constraint's own tolerance is finer).
constexpr double kSkinTolerance = 1e-4;
// contact_scene's obstacle class of the patient's solids as the tool sees them during the task.
constexpr std::string_view kContactClass = "task_contact";

std::string text(const Vector3& v) {
  std::ostringstream out;
  out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return out.str();
}

double point_distance(const Vector3& p, const Shape& shape) {
  const Capsule point{p, p, 0.0};
  return std::visit([&](const auto& s) { return distance(point, s).distance; }, shape);
}

// The patient obstacle nearest to a point (the one the task touches).
const Obstacle& nearest_patient_obstacle(const Scene& scene, const Vector3& p, const char* what) {
  const Obstacle* best = nullptr;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const Obstacle& o : scene.obstacles) {
    if (o.obstacle_class != "patient") continue;
    const double d = std::abs(point_distance(p, o.shape));
    if (d < best_distance) best_distance = d, best = &o;
  }
  if (best == nullptr || best_distance > kContactTolerance)
    throw TaskError(scene.path + ": task: the " + std::string(what) + " " + text(p) +
                    " is not on the patient (no obstacle of class patient within " + std::to_string(kContactTolerance) + " m)");
  return *best;
}

// Closest point of the segment a-b (a point when a == b) to p, and whether it is interior.
Vector3 closest_on_core(const Vector3& a, const Vector3& b, const Vector3& p, bool& interior) {
  const Vector3 d = b - a;
  const double length2 = d.squaredNorm();
  interior = false;
  if (length2 == 0.0) return a;
  const double t = (p - a).dot(d) / length2;
  if (t <= 0.0) return a;
  if (t >= 1.0) return b;
  interior = true;
  return a + t * d;
}

}  // namespace

TaskConstraint::TaskConstraint(const Model& model, const Scene& scene) : model_(model), scene_(scene) {
  if (const auto* scan = std::get_if<UltrasoundScan>(&scene.task)) {
    codim_ = 4;
    const Obstacle& skin = nearest_patient_obstacle(scene, scan->start, "scan start");
    contact_obstacle_ = skin.name;
    if (const auto* c = std::get_if<Capsule>(&skin.shape)) {
      skin_a_ = c->a, skin_b_ = c->b, skin_radius_ = c->radius;
    } else if (const auto* s = std::get_if<Sphere>(&skin.shape)) {
      skin_a_ = skin_b_ = s->center, skin_radius_ = s->radius;
    } else {
      throw TaskError(scene.path + ": task: the scan's skin '" + skin.name + "' must be a capsule or a sphere (its normal field)");
    }
    for (const Vector3& p : {scan->start, Vector3(0.5 * (scan->start + scan->end)), scan->end})
      if (std::abs(point_distance(p, skin.shape)) > kSkinTolerance)
        throw TaskError(scene.path + ": task: the scan line point " + text(p) + " is not on the skin of '" + skin.name +
                        "' (within " + std::to_string(kSkinTolerance) + " m)");
    line_start_ = scan->start;
    line_direction_ = (scan->end - scan->start).normalized();
    const TcpTarget at_start = target(0.0);
    if ((at_start.axis - scan->tool_axis).norm() > 1e-6)
      throw TaskError(scene.path + ": task.tool_axis " + text(scan->tool_axis) + " is not the skin's inward normal " +
                      text(at_start.axis) + " at the scan start");
    plane_normal_ = line_direction_.cross(at_start.axis).normalized();
    progress_start_ = 0.0;
    progress_end_ = (scan->end - scan->start).norm();
    anchor_retract_ = scan->hover;
  } else if (const auto* rcm = std::get_if<RcmPivot>(&scene.task)) {
    codim_ = 2;
    contact_obstacle_ = nearest_patient_obstacle(scene, rcm->trocar, "trocar").name;
    point_ = rcm->trocar;
    insertion_ = 0.5 * (rcm->insertion_min + rcm->insertion_max);
    progress_start_ = -kSweepFraction * rcm->max_pivot;
    progress_end_ = kSweepFraction * rcm->max_pivot;
    anchor_retract_ = rcm->hover;
  } else {
    const auto& burr = std::get<BurrHole>(scene.task);
    codim_ = 4;
    contact_obstacle_ = nearest_patient_obstacle(scene, burr.entry, "burr entry").name;
    point_ = burr.entry;
    axis_ = burr.axis;
    u1_ = axis_.unitOrthogonal();
    u2_ = axis_.cross(u1_);
    const auto patient = scene.clearance.find("patient");
    anchor_retract_ = (patient == scene.clearance.end() ? 0.0 : patient->second) + 0.01;
    if (burr.standoff >= anchor_retract_)
      throw TaskError(scene.path + ": task.standoff " + std::to_string(burr.standoff) + " must be below the approach start " +
                      std::to_string(anchor_retract_) + " m (patient clearance + 0.01)");
    progress_start_ = anchor_retract_;
    progress_end_ = burr.standoff - burr.advance;
  }
}

void TaskConstraint::kinematics(const Vector7& q) {
  forward_kinematics(model_, data_, q);
  zero_jacobian(data_, Frame::kEndEffector, jacobian_);
}

void TaskConstraint::evaluate(const Vector7& q, Eigen::VectorXd& f, Eigen::MatrixXd& J) {
  kinematics(q);
  const Transform& T = frame_pose(data_, Frame::kEndEffector);
  const Vector3 p = T.translation, x = T.rotation.col(0), y = T.rotation.col(1);
  const auto Jv = jacobian_.topRows<3>();
  const auto Jw = jacobian_.bottomRows<3>();
  f.resize(codim_);
  J.resize(codim_, kNumJoints);
  // A frame axis e moves as de/dq_i = omega_i x e, so d(e.w)/dq_i = omega_i.(e x w) for a fixed w.
  if (std::holds_alternative<UltrasoundScan>(scene_.task)) {
    bool interior = false;
    const Vector3 c = closest_on_core(skin_a_, skin_b_, p, interior);
    const double rho = (p - c).norm();
    const Vector3 n = (p - c) / rho;
    // dn/dp = (I - n n^T)(I - u u^T)/rho on the cylinder (u the core's axis, n _|_ u), (I - n n^T)/rho on a cap
    Matrix3 dn = Matrix3::Identity() - n * n.transpose();
    if (interior) {
      const Vector3 u = (skin_b_ - skin_a_).normalized();
      dn -= u * u.transpose();
    }
    dn /= rho;
    f << rho - skin_radius_, x.dot(n), y.dot(n), plane_normal_.dot(p - line_start_);
    J.row(0) = n.transpose() * Jv;
    J.row(1) = x.cross(n).transpose() * Jw + (dn * x).transpose() * Jv;
    J.row(2) = y.cross(n).transpose() * Jw + (dn * y).transpose() * Jv;
    J.row(3) = plane_normal_.transpose() * Jv;
  } else if (std::holds_alternative<RcmPivot>(scene_.task)) {
    // planning-notes section 6: df_x/dq_i = (z_i x x_F).(p_rcm - p_F) - x_F.J_v,i
    const Vector3 r = point_ - p;
    f << x.dot(r), y.dot(r);
    J.row(0) = x.cross(r).transpose() * Jw - x.transpose() * Jv;
    J.row(1) = y.cross(r).transpose() * Jw - y.transpose() * Jv;
  } else {
    f << u1_.dot(p - point_), u2_.dot(p - point_), x.dot(axis_), y.dot(axis_);
    J.row(0) = u1_.transpose() * Jv;
    J.row(1) = u2_.transpose() * Jv;
    J.row(2) = x.cross(axis_).transpose() * Jw;
    J.row(3) = y.cross(axis_).transpose() * Jw;
  }
}

Eigen::VectorXd TaskConstraint::function(const Vector7& q) {
  Eigen::VectorXd f;
  Eigen::MatrixXd J;
  evaluate(q, f, J);
  return f;
}

ConstraintRows TaskConstraint::rows() {
  return [this](const Vector7& q, Eigen::VectorXd& f, Eigen::MatrixXd& J) { evaluate(q, f, J); };
}

double TaskConstraint::progress(const Vector7& q) {
  forward_kinematics(model_, data_, q);
  const Transform& T = frame_pose(data_, Frame::kEndEffector);
  if (std::holds_alternative<UltrasoundScan>(scene_.task)) return line_direction_.dot(T.translation - line_start_);
  if (std::holds_alternative<RcmPivot>(scene_.task)) {
    const Vector3 w = T.rotation.col(2);   // the shaft, pointing into the body
    return std::atan2(w.y(), -w.z());
  }
  return axis_.dot(T.translation - point_);
}

TcpTarget TaskConstraint::target(double s) const {
  if (std::holds_alternative<UltrasoundScan>(scene_.task)) {
    const Vector3 p = line_start_ + s * line_direction_;
    bool interior = false;
    const Vector3 c = closest_on_core(skin_a_, skin_b_, p, interior);
    const Vector3 n = (p - c).normalized();
    return {c + skin_radius_ * n, -n};
  }
  if (std::holds_alternative<RcmPivot>(scene_.task)) {
    const Vector3 w(0.0, std::sin(s), -std::cos(s));
    return {point_ + insertion_ * w, w};
  }
  return {point_ + s * axis_, -axis_};
}

TcpTarget TaskConstraint::anchor_target(double s) const {
  const TcpTarget on_task = target(s);
  const Vector3 contact = std::holds_alternative<UltrasoundScan>(scene_.task) ? on_task.position : point_;
  return {contact - anchor_retract_ * on_task.axis, on_task.axis};
}

bool TaskConstraint::within_ranges(const Vector7& q) {
  const auto* rcm = std::get_if<RcmPivot>(&scene_.task);
  if (rcm == nullptr) return true;
  forward_kinematics(model_, data_, q);
  const Transform& T = frame_pose(data_, Frame::kEndEffector);
  const Vector3 w = T.rotation.col(2);
  const double insertion = w.dot(T.translation - point_);
  const double pivot = std::acos(std::clamp(-w.z(), -1.0, 1.0));
  return insertion >= rcm->insertion_min && insertion <= rcm->insertion_max && pivot <= rcm->max_pivot;
}

Scene contact_scene(const Scene& scene, const std::string& contact_obstacle) {
  // The tool's tip capsule: the one whose end cap is nearest to the TCP.
  const Vector3 tcp = scene.tool.F_T_EE.translation;
  const NamedCapsule* tip = nullptr;
  double best = std::numeric_limits<double>::infinity();
  for (const NamedCapsule& c : scene.tool.capsules) {
    const double d = std::min((c.capsule.a - tcp).norm(), (c.capsule.b - tcp).norm()) - c.capsule.radius;
    if (d < best) best = d, tip = &c;
  }
  Scene out = scene;
  out.clearance[std::string(kContactClass)] = 0.0;
  std::vector<Obstacle> touched;
  for (Obstacle& o : out.obstacles) {
    if (o.obstacle_class != "patient") continue;
    // The arm keeps the patient clearance; the tool may touch the patient (the copy, clearance 0) ...
    Obstacle copy = o;
    copy.name = o.name + "@contact";
    copy.obstacle_class = std::string(kContactClass);
    copy.exempt.clear();
    for (const LinkCapsule& link : franka_arm_capsules()) copy.exempt.emplace_back(link.name);
    // ... and the tip enters the contact obstacle (probe face on the skin, shaft through the port, bit at the bone).
    if (o.name == contact_obstacle && tip != nullptr) copy.exempt.push_back(tip->name);
    for (const NamedCapsule& c : scene.tool.capsules) o.exempt.push_back(c.name);
    touched.push_back(std::move(copy));
  }
  out.obstacles.insert(out.obstacles.end(), touched.begin(), touched.end());
  return out;
}

namespace {

// The named pose whose TCP is nearest to a target: the IK seed (its branch is the scene's).
const NamedPose& nearest_pose(const Scene& scene, const Model& model, const Vector3& position) {
  Data data;
  const NamedPose* best = &scene.poses.front();
  double best_distance = std::numeric_limits<double>::infinity();
  for (const NamedPose& pose : scene.poses) {
    forward_kinematics(model, data, pose.q);
    const double d = (frame_pose(data, Frame::kEndEffector).translation - position).norm();
    if (d < best_distance) best_distance = d, best = &pose;
  }
  return *best;
}

// IK to a TCP target from a seed, with the clearance/limit null-space term; throws TaskError
// naming the scene and `what` if it does not converge, collides or leaves the seed's branch.
Vector7 solve_target(TaskConstraint& task, const TcpTarget& target, const Vector7& seed, const std::string& seed_name,
                     ClearanceChecker& checker, const std::string& what, bool on_task) {
  const Model& model = task.model();
  const std::string where = task.scene().path + ": task: the " + what + " (TCP " + text(target.position) + ", axis " +
                            text(target.axis) + ")";
  IkOptions options;
  options.max_iterations = 200;
  options.tolerance = 1e-9;
  const IkResult reach = solve_ik(tcp_target_rows(model, target.position, target.axis), seed,
                                  model.parameters().joint_limits, nullptr, options);
  if (!reach.converged)
    throw TaskError(where + " is unreachable: inverse kinematics from pose '" + seed_name + "' stops " +
                    std::to_string(reach.residual) + " from it (within the joint limits)");
  options.nullspace_gain = 0.05;   // then more clearance, away from the limits, with the target held
  const IkResult result = solve_ik(tcp_target_rows(model, target.position, target.axis), reach.q,
                                   model.parameters().joint_limits, &checker, options);
  const Vector7 q = result.converged ? result.q : reach.q;
  const StateClearance c = checker.check(q);
  if (c.clearance < 0.0)
    throw TaskError(where + " is in collision: " + std::string(c.moving) + " vs " + std::string(c.other) + " (" +
                    std::string(c.obstacle_class) + ") by " + std::to_string(-c.clearance) + " m");
  if (on_task && !task.within_ranges(q)) throw TaskError(where + " is outside the task's insertion or pivot range");
  if (!(ik_branch(model, q) == ik_branch(model, seed)))
    throw TaskError(where + ": inverse kinematics left the IK branch of pose '" + seed_name + "'");
  return q;
}

}  // namespace

Vector7 task_anchor(TaskConstraint& task, double progress, const Vector7& q_task, ClearanceChecker& scene_checker) {
  return solve_target(task, task.anchor_target(progress), q_task, "task configuration", scene_checker,
                      "excitation anchor at progress " + std::to_string(progress), false);
}

TaskStates task_states(TaskConstraint& task, ClearanceChecker& contact_checker, ClearanceChecker& scene_checker) {
  const Scene& scene = task.scene();
  if (scene.poses.empty()) throw TaskError(scene.path + ": poses: the task's IK needs at least one named pose as a seed");
  TaskStates states;
  const auto solve = [&](double progress, const char* what) {
    const TcpTarget target = task.target(progress);
    const NamedPose& seed = nearest_pose(scene, task.model(), target.position);
    return solve_target(task, target, seed.q, seed.name, contact_checker, what, true);
  };
  states.start = solve(task.progress_start(), "task start");
  states.end = solve(task.progress_end(), "task end");
  states.anchors.push_back(task_anchor(task, task.progress_start(), states.start, scene_checker));
  if ((task.anchor_target(task.progress_end()).position - task.anchor_target(task.progress_start()).position).norm() > 1e-9)
    states.anchors.push_back(task_anchor(task, task.progress_end(), states.end, scene_checker));
  return states;
}

}  // namespace csp::planners
