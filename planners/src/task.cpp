#include "csp/planners/task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <unsupported/Eigen/Splines>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/geometry.hpp"
#include "csp/planners/ompl_bridge.hpp"
#include "csp/planners/profile.hpp"

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

TcpTarget TaskConstraint::anchor_target(const Vector7& q) {
  forward_kinematics(model_, data_, q);
  const Transform& T = frame_pose(data_, Frame::kEndEffector);
  const Vector3 axis = T.rotation.col(2);
  const Vector3 contact = std::holds_alternative<UltrasoundScan>(scene_.task) ? T.translation : point_;
  return {contact - anchor_retract_ * axis, axis};
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
  const int tip = tool_tip_capsule(scene.tool);
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
    if (o.name == contact_obstacle && tip >= 0) copy.exempt.push_back(scene.tool.capsules[tip].name);
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

Vector7 task_anchor(TaskConstraint& task, const Vector7& q_task, ClearanceChecker& scene_checker) {
  return solve_target(task, task.anchor_target(q_task), q_task, "task configuration", scene_checker,
                      "excitation anchor at progress " + std::to_string(task.progress(q_task)), false);
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
  states.anchors.push_back(task_anchor(task, states.start, scene_checker));
  if ((task.anchor_target(task.progress_end()).position - task.anchor_target(task.progress_start()).position).norm() > 1e-9)
    states.anchors.push_back(task_anchor(task, states.end, scene_checker));
  return states;
}

namespace {

// ---- Geometry of the path: dense states on the manifold, then q(progress) ----

// Newton projection of q onto the manifold (minimum-norm steps, no secondary objective).
Vector7 project(TaskConstraint& task, const Vector7& q, const JointLimits& limits) {
  IkOptions options;
  options.max_iterations = 50;
  options.tolerance = 1e-10;
  options.limit_margin = 0.0;
  const IkResult r = solve_ik(task.rows(), q, limits, nullptr, options);
  if (!r.converged)
    throw TaskError(task.scene().path + ": task: a path state does not project onto the constraint manifold (|f| " +
                    std::to_string(r.residual) + ")");
  return r.q;
}

// The planner's states, cut so that no joint moves more than delta/2 between two, each projected.
std::vector<Vector7> densify(TaskConstraint& task, const std::vector<Vector7>& waypoints, double delta,
                             const JointLimits& limits) {
  std::vector<Vector7> states{waypoints.front()};
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const Vector7 step = waypoints[i] - waypoints[i - 1];
    if (step.isZero(0.0)) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(step.cwiseAbs().maxCoeff() / (0.5 * delta))));
    for (int k = 1; k <= n; ++k)
      states.push_back(project(task, waypoints[i - 1] + (static_cast<double>(k) / n) * step, limits));
  }
  return states;
}

using JointSpline = Eigen::Spline<double, kNumJoints>;

// q as a quintic B-spline of the progress, through the path resampled at uniform progress steps
// (each sample linearly interpolated in progress between the two dense states around it, then
// projected): uniform knots keep the interpolation well conditioned.
struct ProgressPath {
  JointSpline spline;
  double from = 0.0, to = 0.0;   // progress at u = 0 and u = 1
  // q and its first three derivatives with respect to the progress.
  std::array<Vector7, 4> at(double progress) const {
    const double scale = 1.0 / (to - from);
    const auto d = spline.derivatives(std::clamp((progress - from) * scale, 0.0, 1.0), 3);
    std::array<Vector7, 4> out;
    double factor = 1.0;
    for (int k = 0; k < 4; ++k, factor *= scale) out[static_cast<std::size_t>(k)] = d.col(k) * factor;
    return out;
  }
};

ProgressPath progress_path(TaskConstraint& task, const std::vector<Vector7>& states, const std::vector<double>& progress,
                           double delta, const JointLimits& limits) {
  double travel = 0.0;
  for (std::size_t i = 1; i < states.size(); ++i) travel += (states[i] - states[i - 1]).cwiseAbs().maxCoeff();
  const int n = std::max(8, static_cast<int>(std::ceil(travel / delta)));
  Eigen::Matrix<double, kNumJoints, Eigen::Dynamic> points(kNumJoints, n + 1);
  Eigen::RowVectorXd knots(n + 1);
  ProgressPath path{JointSpline(), progress.front(), progress.back()};
  const double sign = path.to > path.from ? 1.0 : -1.0;
  std::size_t i = 1;
  for (int k = 0; k <= n; ++k) {
    const double u = static_cast<double>(k) / n;
    const double s = path.from + u * (path.to - path.from);
    while (i + 1 < progress.size() && sign * (progress[i] - s) < 0.0) ++i;
    const double w = std::clamp((s - progress[i - 1]) / (progress[i] - progress[i - 1]), 0.0, 1.0);
    const Vector7 q = states[i - 1] + w * (states[i] - states[i - 1]);
    points.col(k) = (k == 0 || k == n) ? q : project(task, q, limits);
    knots[k] = u;
  }
  path.spline = Eigen::SplineFitting<JointSpline>::Interpolate(points, 5, knots);
  return path;
}

// ---- Timing: the progress as a function of time ----

// int_0^u s(v) dv of the septic step (profile.hpp): the distance covered by a septic velocity ramp,
// 1/2 at u = 1.
double septic_integral(double u) {
  const double u5 = u * u * u * u * u;
  return u5 * (7.0 - 14.0 * u + 10.0 * u * u - 2.5 * u * u * u);
}

// One piece of the time law: rest to rest (septic in time) from `from` to `to`, or at constant
// speed with septic velocity ramps of `ramp` seconds at both ends.
struct TimedSegment {
  double from = 0.0, to = 0.0;
  double speed = 0.0;   // > 0: cruise at this speed [progress/s]
  double duration = 0.0, ramp = 0.0;

  // The progress and its first three time derivatives at time t in [0, duration].
  std::array<double, 4> at(double t) const {
    if (speed <= 0.0) {
      const SepticSample s = septic(t / duration);
      const double d = to - from;
      return {from + d * s.s, d * s.ds / duration, d * s.dds / (duration * duration), d * s.ddds / (duration * duration * duration)};
    }
    const double v = (to > from ? 1.0 : -1.0) * speed, cruise_end = duration - ramp;
    if (t < ramp) {   // velocity v s(t/ramp)
      const double u = std::max(t, 0.0) / ramp;
      const SepticSample s = septic(u);
      return {from + v * ramp * septic_integral(u), v * s.s, v * s.ds / ramp, v * s.dds / (ramp * ramp)};
    }
    if (t <= cruise_end) return {from + v * (0.5 * ramp + (t - ramp)), v, 0.0, 0.0};
    const double u = std::min((t - cruise_end) / ramp, 1.0);   // velocity v (1 - s(u))
    const SepticSample s = septic(u);
    return {from + v * (0.5 * ramp + (cruise_end - ramp) + ramp * (u - septic_integral(u))), v * (1.0 - s.s),
            -v * s.ds / ramp, -v * s.dds / (ramp * ramp)};
  }
};

// Per joint, the maxima over the progress range of |dq/ds|, |d2q/ds2|, |d3q/ds3| (dense sampling).
std::array<Vector7, 3> path_derivative_bounds(const ProgressPath& path, double from, double to) {
  std::array<Vector7, 3> bound{Vector7::Zero(), Vector7::Zero(), Vector7::Zero()};
  constexpr int kSamples = 2000;
  for (int k = 0; k <= kSamples; ++k) {
    const auto d = path.at(from + (to - from) * k / kSamples);
    for (std::size_t i = 0; i < 3; ++i) bound[i] = bound[i].cwiseMax(d[i + 1].cwiseAbs());
  }
  return bound;
}

// The maximum over the progress range of the TCP's rate |dp/ds| (finite differences between dense samples).
double tcp_rate_bound(const Model& model, const ProgressPath& path, double from, double to) {
  Data data;
  constexpr int kSamples = 2000;
  double bound = 0.0;
  Vector3 previous = Vector3::Zero();
  for (int k = 0; k <= kSamples; ++k) {
    forward_kinematics(model, data, path.at(from + (to - from) * k / kSamples)[0]);
    const Vector3 p = frame_pose(data, Frame::kEndEffector).translation;
    if (k > 0) bound = std::max(bound, (p - previous).norm() / (std::abs(to - from) / kSamples));
    previous = p;
  }
  return bound;
}

double ceil_ms(double t) { return std::ceil(t * 1000.0 - 1e-9) / 1000.0; }

// The shortest rest-to-rest duration (at least `minimum`) whose joint velocity, acceleration and jerk
// stay within v, a, j, by the chain rule with each factor at its peak (a guaranteed bound), D = |to - from|:
//   |dq| <= Q1 p1 D/T,  |ddq| <= (Q2 p1^2 D^2 + Q1 p2 D)/T^2,  |dddq| <= (Q3 p1^3 D^3 + 3 Q2 p1 p2 D^2 + Q1 p3 D)/T^3
double rest_to_rest_duration(const std::array<Vector7, 3>& Q, double D, const Vector7& v, const Vector7& a,
                             const Vector7& j, double minimum) {
  const double p1 = kSepticPeakVelocity, p2 = kSepticPeakAcceleration, p3 = kSepticPeakJerk;
  double T = minimum;
  for (int i = 0; i < kNumJoints; ++i) {
    T = std::max(T, Q[0][i] * p1 * D / v[i]);
    T = std::max(T, std::sqrt((Q[1][i] * p1 * p1 * D * D + Q[0][i] * p2 * D) / a[i]));
    T = std::max(T, std::cbrt((Q[2][i] * std::pow(p1 * D, 3) + 3.0 * Q[1][i] * p1 * p2 * D * D + Q[0][i] * p3 * D) / j[i]));
  }
  return ceil_ms(T);
}

// A constant-speed segment: the shortest velocity ramp R (at least `minimum`) within the limits, with
//   |dq| <= Q1 V,  |ddq| <= Q2 V^2 + Q1 p1 V/R,  |dddq| <= Q3 V^3 + 3 Q2 p1 V^2/R + Q1 p2 V/R^2.
// Throws when the speed itself, or the ramps that fit in the segment, exceed the limits.
TimedSegment cruise_segment(const std::string& where, const std::array<Vector7, 3>& Q, double from, double to,
                            double speed, const Vector7& v, const Vector7& a, const Vector7& j, double minimum) {
  const double p1 = kSepticPeakVelocity, p2 = kSepticPeakAcceleration;
  const double L = std::abs(to - from);
  const auto fits = [&](double R) {
    for (int i = 0; i < kNumJoints; ++i) {
      if (Q[0][i] * speed > v[i]) return false;
      if (Q[1][i] * speed * speed + Q[0][i] * p1 * speed / R > a[i]) return false;
      if (Q[2][i] * std::pow(speed, 3) + 3.0 * Q[1][i] * p1 * speed * speed / R + Q[0][i] * p2 * speed / (R * R) > j[i])
        return false;
    }
    return true;
  };
  double R = minimum;
  while (!fits(R) && R * speed < L) R *= 1.25;
  R = std::min(ceil_ms(R), L / speed);
  if (!fits(R)) throw TaskError(where + ": the task speed " + std::to_string(speed) + " exceeds the joint limits along the path");
  return {from, to, speed, R + L / speed, R};   // the two half ramps cover speed R, the cruise the rest
}

}  // namespace

TaskPath plan_task_path(const Scene& scene, const Model& model, const TaskPathOptions& options) {
  TaskConstraint task(model, scene);
  ClearanceChecker contact(model, contact_scene(scene, task.contact_obstacle()));
  ClearanceChecker plain(model, scene);
  const JointLimits& limits = model.parameters().joint_limits;
  const std::string where = scene.path + ": task";

  TaskPath path;
  path.scene = scene.name;
  path.codim = task.codim();
  const TaskStates states = task_states(task, contact, plain);
  path.start = states.start;
  path.end = states.end;
  path.anchors = states.anchors;

  // The path on the manifold (OMPL, planners/ompl_bridge).
  ompl_bridge::Request request;
  Vector7::Map(request.start.data()) = states.start;
  Vector7::Map(request.goal.data()) = states.end;
  // The joints stay within the task's range +- joint_margin (planning-notes section 1, the task
  // envelope): random samples near the task keep OMPL's geodesics toward them short.
  Vector7::Map(request.lower.data()) = (states.start.cwiseMin(states.end).array() - options.joint_margin).max(limits.q_min.array());
  Vector7::Map(request.upper.data()) = (states.start.cwiseMax(states.end).array() + options.joint_margin).min(limits.q_max.array());
  request.seed = options.seed;
  request.max_iterations = options.max_iterations;
  request.range = options.range;
  request.simplify_steps = options.simplify_steps;
  ompl_bridge::Callbacks callbacks;
  callbacks.is_valid = [&](const ompl_bridge::Joints& q) {
    const Vector7 v = Vector7::Map(q.data());
    return contact.is_valid(v) && task.within_ranges(v);
  };
  ompl_bridge::ManifoldConstraint constraint;
  constraint.codimension = task.codim();
  constraint.tolerance = options.tolerance;
  constraint.delta = options.delta;
  Eigen::VectorXd f;
  Eigen::MatrixXd J;
  constraint.function = [&](const double* q, double* out) {
    task.evaluate(Vector7::Map(q), f, J);
    Eigen::VectorXd::Map(out, f.size()) = f;
  };
  if (options.analytic_jacobian)
    constraint.jacobian = [&](const double* q, double* out) {
      task.evaluate(Vector7::Map(q), f, J);
      Eigen::Matrix<double, Eigen::Dynamic, kNumJoints, Eigen::RowMajor>::Map(out, J.rows(), kNumJoints) = J;
    };
  const ompl_bridge::Result planned = ompl_bridge::plan_on_manifold(request, callbacks, constraint);
  path.iterations = static_cast<int>(planned.iterations);
  path.planning_seconds = planned.seconds;
  if (!planned.solved) {
    path.message = where + ": no path on the constraint manifold: " + planned.message;
    return path;
  }
  path.status = PlannerStatus::kExactSolution;
  for (const auto& q : planned.waypoints) path.waypoints.push_back(Vector7::Map(q.data()));

  // Dense states on the manifold, each valid and each chord certified free.
  path.states = densify(task, path.waypoints, options.delta, limits);
  for (std::size_t i = 0; i < path.states.size(); ++i) {
    const Vector7& q = path.states[i];
    if (!contact.is_valid(q) || !task.within_ranges(q) || (i > 0 && !contact.motion_is_free(path.states[i - 1], q)))
      throw TaskError(where + ": the densified path leaves the free space at state " + std::to_string(i));
    path.progress.push_back(task.progress(q));
  }
  // The path parameter the time law runs along: the task progress (scan distance, drill height),
  // which must then advance at every state; for the rcm sweep (5-D manifold: the other pivot
  // direction, the insertion and the roll are free) the path's joint-space arc length.
  const bool by_arc_length = std::holds_alternative<RcmPivot>(scene.task);
  std::vector<double> parameter{by_arc_length ? 0.0 : path.progress.front()};
  for (std::size_t i = 1; i < path.states.size(); ++i) {
    parameter.push_back(by_arc_length ? parameter.back() + (path.states[i] - path.states[i - 1]).norm() : path.progress[i]);
    const double sign = by_arc_length || task.progress_end() > task.progress_start() ? 1.0 : -1.0;
    if (sign * (parameter[i] - parameter[i - 1]) <= 0.0)
      throw TaskError(where + ": the planned path does not advance along the task at state " + std::to_string(i) +
                      " (progress " + std::to_string(parameter[i - 1]) + " -> " + std::to_string(parameter[i]) + ")");
  }
  const ProgressPath geometry = progress_path(task, path.states, parameter, options.delta, limits);

  // The time law along the task.
  const Vector7 v = options.velocity_fraction * limits.dq_max;
  const Vector7 a = options.acceleration_fraction * limits.ddq_max;
  const Vector7 jerk = options.jerk_fraction * limits.dddq_max;
  constexpr double kMinimum = 1.0;   // no segment or ramp shorter than 1 s near the patient
  std::vector<TimedSegment> segments;
  const auto rest_to_rest = [&](double from, double to) {
    const double D = std::abs(to - from);
    // and the TCP no faster than tool_speed: |dp/dt| <= P1 p1 D/T
    const double tool = kSepticPeakVelocity * D * tcp_rate_bound(model, geometry, from, to) / options.tool_speed;
    const double T = rest_to_rest_duration(path_derivative_bounds(geometry, from, to), D, v, a, jerk, std::max(kMinimum, tool));
    segments.push_back({from, to, 0.0, T, 0.0});
  };
  const auto cruise = [&](double from, double to, double speed) {
    segments.push_back(cruise_segment(where, path_derivative_bounds(geometry, from, to), from, to, speed, v, a, jerk, kMinimum));
  };
  if (const auto* scan = std::get_if<UltrasoundScan>(&scene.task)) {
    cruise(task.progress_start(), task.progress_end(), scan->speed);
  } else if (by_arc_length) {
    rest_to_rest(0.0, parameter.back());
  } else {
    const auto& burr = std::get<BurrHole>(scene.task);
    rest_to_rest(task.progress_start(), burr.standoff);
    cruise(burr.standoff, task.progress_end(), burr.speed);
  }

  // Sampled at rate_hz by the chain rule (Q1..Q3: derivatives of q along the path, s1..s3: of the
  // path parameter in time): dq = Q1 s1, ddq = Q2 s1^2 + Q1 s2, dddq = Q3 s1^3 + 3 Q2 s1 s2 + Q1 s3.
  double offset = 0.0;
  for (const TimedSegment& segment : segments) offset += segment.duration;
  const auto sample = [&](double t) {
    std::size_t i = 0;
    double start = 0.0;
    while (i + 1 < segments.size() && t >= start + segments[i].duration) start += segments[i++].duration;
    const auto s = segments[i].at(t - start);
    const auto Q = geometry.at(s[0]);
    JointSample out;
    out.q = Q[0];
    out.dq = Q[1] * s[1];
    out.ddq = Q[2] * s[1] * s[1] + Q[1] * s[2];
    out.dddq = Q[3] * s[1] * s[1] * s[1] + 3.0 * Q[2] * s[1] * s[2] + Q[1] * s[3];
    return out;
  };
  path.log = sampled_joint_log(sample, offset, options.rate_hz, model, "task path " + scene.name);
  path.duration = offset;
  return path;
}

}  // namespace csp::planners
