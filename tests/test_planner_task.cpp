// The medical task paths (planners/task.hpp, ik.hpp) against independent references: central
// finite differences of the constraints, KDL's forward kinematics of the IK results, the skin,
// trocar and burr geometry recomputed from the scene at every 1 kHz sample, and a dense re-check by
// a ClearanceChecker of its own.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/ik.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/task.hpp"
#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using planners::ClearanceChecker;
using planners::TaskConstraint;

const std::vector<std::string> kScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};

std::string scene_file(const std::string& name) { return std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + name + ".yaml"; }

Model scene_model(const std::string& robot, const Scene& scene) {
  return Model(with_tool(model_parameters(load_robot_config(robot_file(robot)), {}), scene.tool));
}

// ---------------- Constraint Jacobians vs central differences ----------------

// The analytic Jacobian of `rows` at q against central differences (h = 1e-6).
void expect_jacobian_matches_central_differences(const planners::ConstraintRows& rows, const Vector7& q) {
  Eigen::VectorXd f, plus_f, minus_f;
  Eigen::MatrixXd J, unused;
  rows(q, f, J);
  ASSERT_EQ(J.rows(), f.size());
  constexpr double h = 1e-6;
  for (int j = 0; j < kNumJoints; ++j) {
    Vector7 plus = q, minus = q;
    plus[j] += h;
    minus[j] -= h;
    rows(plus, plus_f, unused);
    rows(minus, minus_f, unused);
    const Eigen::VectorXd fd = (plus_f - minus_f) / (2.0 * h);
    for (int r = 0; r < f.size(); ++r) EXPECT_NEAR(J(r, j), fd[r], 1e-7 * (1.0 + std::abs(fd[r]))) << "row " << r << " joint " << j;
  }
}

TEST(TaskConstraint, AnalyticJacobianMatchesCentralDifferences) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (const auto& name : kScenes) {
    SCOPED_TRACE(name);
    const Scene scene = load_scene(scene_file(name));
    const Model model = scene_model("panda", scene);
    TaskConstraint task(model, scene);
    EXPECT_EQ(task.codim(), std::holds_alternative<RcmPivot>(scene.task) ? 2 : 4);
    for (int trial = 0; trial < 50; ++trial) {
      // Around the scene's poses (near the task, where the skin normal's cylinder part applies) and far from it.
      Vector7 q = scene.poses[trial % scene.poses.size()].q;
      for (int j = 0; j < kNumJoints; ++j) q[j] += noise(rng);
      expect_jacobian_matches_central_differences(task.rows(), q);
    }
  }
}

TEST(Ik, TcpTargetRowsJacobianMatchesCentralDifferences) {
  const Scene scene = load_scene(scene_file("craniotomy"));
  const Model model = scene_model("fr3", scene);
  const auto rows = planners::tcp_target_rows(model, Vector3(0.4, 0.1, 0.3), Vector3(0.0, 0.6, -0.8));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    Vector7 q;
    for (int j = 0; j < kNumJoints; ++j) q[j] = u(rng);
    expect_jacobian_matches_central_differences(rows, q);
  }
}

// ---------------- IK: task states and anchors ----------------

// The TCP of q by KDL's forward kinematics (an independent chain).
Transform kdl_tcp(KdlPeer& kdl, const Vector7& q) { return kdl.ee_pose(q); }

#ifdef CSP_TASK_TESTS_REDUCED
const std::vector<std::string> kStateRobots = {"panda"};   // sanitized build: the IK once per scene
#else
const std::vector<std::string> kStateRobots = {"panda", "fr3"};
#endif

TEST(TaskStates, StartEndAndAnchorsHitTheirTargetsByKdlAndKeepTheScenesBranch) {
  for (const std::string& robot : kStateRobots)
    for (const auto& name : kScenes) {
      SCOPED_TRACE(robot + " " + name);
      const Scene scene = load_scene(scene_file(name));
      const Model model = scene_model(robot, scene);
      TaskConstraint task(model, scene);
      ClearanceChecker contact(model, planners::contact_scene(scene, task.contact_obstacle()));
      ClearanceChecker plain(model, scene);
      const planners::TaskStates states = planners::task_states(task, contact, plain);
      KdlPeer kdl(model);
      const auto expect_at = [&](const Vector7& q, const planners::TcpTarget& target) {
        const Transform T = kdl_tcp(kdl, q);
        EXPECT_LT((T.translation - target.position).norm(), 1e-7);
        EXPECT_LT((T.rotation.col(2) - target.axis).norm(), 1e-7);
        const JointLimits& limits = model.parameters().joint_limits;
        EXPECT_TRUE((q.array() >= limits.q_min.array()).all() && (q.array() <= limits.q_max.array()).all());
      };
      expect_at(states.start, task.target(task.progress_start()));
      expect_at(states.end, task.target(task.progress_end()));
      EXPECT_LT(task.function(states.start).norm(), 1e-7);
      EXPECT_LT(task.function(states.end).norm(), 1e-7);
      EXPECT_GE(contact.check(states.start).clearance, 0.0);
      EXPECT_GE(contact.check(states.end).clearance, 0.0);
      ASSERT_FALSE(states.anchors.empty());
      expect_at(states.anchors.front(), task.anchor_target(task.progress_start()));
      expect_at(states.anchors.back(), task.anchor_target(task.progress_end()));
      for (const Vector7& anchor : states.anchors) {
        EXPECT_GE(plain.check(anchor).clearance, 0.0);   // contact-free: the scene's own clearances
        EXPECT_TRUE(planners::ik_branch(model, anchor) == planners::ik_branch(model, states.start));
      }
    }
}

// The anchors land where the scenes' named hover poses put the TCP, on their branch.
TEST(TaskStates, AnchorsMatchTheScenesNamedHoverPoses) {
  struct Case {
    std::string scene, pose;
    bool at_start;
  };
  for (const Case& c : {Case{"ultrasound_abdomen", "scan_start_hover", true}, Case{"ultrasound_abdomen", "scan_end_hover", false},
                        Case{"doppler_femoral", "scan_start_hover", true}, Case{"doppler_femoral", "scan_end_hover", false},
                        Case{"craniotomy", "burr_hover", true}}) {
    SCOPED_TRACE(c.scene + " " + c.pose);
    const Scene scene = load_scene(scene_file(c.scene));
    const Model model = scene_model("panda", scene);
    TaskConstraint task(model, scene);
    ClearanceChecker contact(model, planners::contact_scene(scene, task.contact_obstacle()));
    ClearanceChecker plain(model, scene);
    const planners::TaskStates states = planners::task_states(task, contact, plain);
    const Vector7& anchor = c.at_start ? states.anchors.front() : states.anchors.back();
    KdlPeer kdl(model);
    const Vector7& named = scene.pose(c.pose).q;
    EXPECT_LT((kdl_tcp(kdl, anchor).translation - kdl_tcp(kdl, named).translation).norm(), 1e-6);
    EXPECT_LT((kdl_tcp(kdl, anchor).rotation.col(2) - kdl_tcp(kdl, named).rotation.col(2)).norm(), 1e-6);
    EXPECT_TRUE(planners::ik_branch(model, anchor) == planners::ik_branch(model, named));
    // Same TCP, same branch; the redundancy (null-space term) may differ: reported, not asserted.
    std::cout << c.scene << " " << c.pose << ": anchor vs named pose, joint distance " << (anchor - named).norm()
              << " rad, clearance " << plain.check(anchor).clearance << " vs " << plain.check(named).clearance << " m\n";
  }
}

// ---------------- The planned, timed task path at 1 kHz ----------------

// The skin's inward normal and distance at p, recomputed from the scene's obstacle (capsule core).
struct SkinPoint {
  double distance;
  Vector3 inward;
};
SkinPoint skin_at(const Capsule& c, const Vector3& p) {
  const Vector3 d = c.b - c.a;
  const double t = std::clamp((p - c.a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  const Vector3 r = p - (c.a + t * d);
  return {r.norm() - c.radius, -r.normalized()};
}

double angle(const Vector3& a, const Vector3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

#ifdef CSP_TASK_TESTS_REDUCED
const std::vector<std::string> kPathScenes = {"mis_rcm"};   // sanitized build: the OMPL set-up and solve once
#else
const std::vector<std::string> kPathScenes = kScenes;
#endif

TEST(TaskPath, OnTheManifoldWithinLimitsAndCollisionFreeAt1kHz) {
  for (const std::string robot : {"panda", "fr3"})
    for (const auto& name : kPathScenes) {
      SCOPED_TRACE(robot + " " + name);
      const Scene scene = load_scene(scene_file(name));
      const Model model = scene_model(robot, scene);
      const planners::TaskPathOptions options;
      const planners::TaskPath path = planners::plan_task_path(scene, model, options);
      const JointLog& log = path.log;
      ASSERT_GT(log.t.size(), 1000u);
      std::cout << robot << " " << name << ": " << path.waypoints.size() << " waypoints, " << path.states.size() << " states, "
                << path.iterations << " iterations, " << path.planning_seconds << " s planning, duration " << path.duration
                << " s\n";

      // Dense states: joint steps <= delta.
      for (std::size_t i = 1; i < path.states.size(); ++i)
        EXPECT_LE((path.states[i] - path.states[i - 1]).cwiseAbs().maxCoeff(), options.delta + 1e-12);

      // Rest to rest; limits with the fractions asked (jerk by finite differences at 1 kHz, as the robot sees it).
      const JointLimits& limits = model.parameters().joint_limits;
      EXPECT_LT(log.dq.front().norm(), 1e-9);
      EXPECT_LT(log.dq.back().norm(), 1e-9);
      EXPECT_LT(log.ddq.front().norm(), 1e-9);
      EXPECT_LT(log.ddq.back().norm(), 1e-6);
      double worst_v = 0.0, worst_a = 0.0, worst_j = 0.0;
      for (std::size_t k = 0; k < log.t.size(); ++k) {
        EXPECT_NEAR(log.t[k], 1e-3 * static_cast<double>(k), 1e-12);
        worst_v = std::max(worst_v, (log.dq[k].cwiseAbs().array() / limits.dq_max.array()).maxCoeff());
        worst_a = std::max(worst_a, (log.ddq[k].cwiseAbs().array() / limits.ddq_max.array()).maxCoeff());
        if (k > 0) worst_j = std::max(worst_j, ((log.ddq[k] - log.ddq[k - 1]).cwiseAbs().array() / 1e-3 / limits.dddq_max.array()).maxCoeff());
        EXPECT_TRUE((log.q[k].array() >= limits.q_min.array()).all() && (log.q[k].array() <= limits.q_max.array()).all());
        // FR3: the position-based velocity bounds too
        EXPECT_TRUE((log.dq[k].array() <= limits.dq_upper(log.q[k]).array()).all() &&
                    (log.dq[k].array() >= limits.dq_lower(log.q[k]).array()).all());
      }
      EXPECT_LE(worst_v, options.velocity_fraction + 1e-9);
      EXPECT_LE(worst_a, options.acceleration_fraction + 1e-9);
      EXPECT_LE(worst_j, options.jerk_fraction + 1e-3);
      std::cout << "  peak fractions of the limits: velocity " << worst_v << ", acceleration " << worst_a << ", jerk " << worst_j << "\n";

      // Every sample valid when re-checked by a checker of its own (the task's contact scene).
      TaskConstraint task(model, scene);
      ClearanceChecker checker(model, planners::contact_scene(scene, task.contact_obstacle()));
      double min_clearance = 1e9;
      for (const Vector7& q : log.q) min_clearance = std::min(min_clearance, checker.check(q).clearance);
      EXPECT_GE(min_clearance, 0.0);

      // The task geometry at every sample, from KDL's forward kinematics and the scene's numbers.
      KdlPeer kdl(model);
      double worst_position = 0.0, worst_angle = 0.0, peak_speed = 0.0;
      Vector3 previous = kdl_tcp(kdl, log.q.front()).translation;
      for (const Vector7& q : log.q) {
        const Transform T = kdl_tcp(kdl, q);
        const Vector3 p = T.translation, z = T.rotation.col(2);
        peak_speed = std::max(peak_speed, (p - previous).norm() / 1e-3);
        previous = p;
        if (const auto* scan = std::get_if<UltrasoundScan>(&scene.task)) {
          const auto& skin = std::get<Capsule>(std::find_if(scene.obstacles.begin(), scene.obstacles.end(), [&](const auto& o) {
                                                 return o.name == task.contact_obstacle();
                                               })->shape);
          const SkinPoint sp = skin_at(skin, p);
          const Vector3 line = (scan->end - scan->start).normalized();
          const Vector3 off_line = (p - scan->start) - (p - scan->start).dot(line) * line;
          worst_position = std::max({worst_position, std::abs(sp.distance), off_line.norm()});
          worst_angle = std::max(worst_angle, angle(z, sp.inward));
        } else if (const auto* rcm = std::get_if<RcmPivot>(&scene.task)) {
          worst_position = std::max(worst_position, (rcm->trocar - p).cross(z).norm());
          const double insertion = z.dot(p - rcm->trocar);
          EXPECT_TRUE(insertion >= rcm->insertion_min - 1e-9 && insertion <= rcm->insertion_max + 1e-9) << insertion;
          EXPECT_LE(angle(z, -Vector3::UnitZ()), rcm->max_pivot + 1e-9);
        } else {
          const auto& burr = std::get<BurrHole>(scene.task);
          worst_position = std::max(worst_position, (p - burr.entry).cross(burr.axis).norm());
          worst_angle = std::max(worst_angle, angle(z, -burr.axis));
        }
      }
      EXPECT_LE(worst_position, 1e-4);   // issue 13: within 0.1 mm
      EXPECT_LE(worst_angle, 1e-3);
      std::cout << "  worst distance from the task geometry " << worst_position << " m, worst axis angle " << worst_angle
                << " rad, min clearance " << min_clearance << " m, peak TCP speed " << peak_speed << " m/s\n";

      // The anchor of a task configuration mid-path: its TCP retracted along its own tool axis (KDL),
      // contact-free in the scene itself.
      {
        const Vector7& middle = path.states[path.states.size() / 2];
        ClearanceChecker plain(model, scene);
        const Vector7 anchor = planners::task_anchor(task, middle, plain);
        const Transform at_middle = kdl_tcp(kdl, middle), at_anchor = kdl_tcp(kdl, anchor);
        EXPECT_LT((at_anchor.rotation.col(2) - at_middle.rotation.col(2)).norm(), 1e-7);
        const Vector3 back = at_middle.translation - at_anchor.translation;   // along +z, by the retract (+ insertion)
        EXPECT_LT(back.cross(at_middle.rotation.col(2)).norm(), 1e-7);
        EXPECT_GE(plain.check(anchor).clearance, 0.0);
      }

      // Timed along the task: the scan at its speed; the drill ends advanced by `advance` past its standoff.
      const Transform end = kdl_tcp(kdl, log.q.back());
      if (const auto* scan = std::get_if<UltrasoundScan>(&scene.task)) {
        EXPECT_NEAR(peak_speed, scan->speed, 1e-3 * scan->speed);
        EXPECT_LT((end.translation - scan->end).norm(), 1e-4);
      } else if (const auto* burr = std::get_if<BurrHole>(&scene.task)) {
        EXPECT_NEAR(burr->axis.dot(end.translation - burr->entry), burr->standoff - burr->advance, 1e-6);
      }
    }
}

// The same seed gives the same path, sample for sample (iteration caps, no clock).
TEST(TaskPath, SameSeedSamePath) {
#ifdef CSP_TASK_TESTS_REDUCED
  GTEST_SKIP() << "sanitized build: determinism is checked in the Release build";
#endif
  const Scene scene = load_scene(scene_file("mis_rcm"));
  const Model model = scene_model("panda", scene);
  planners::TaskPathOptions options;
  options.seed = 7;
  const planners::TaskPath a = planners::plan_task_path(scene, model, options);
  const planners::TaskPath b = planners::plan_task_path(scene, model, options);
  ASSERT_EQ(a.status, planners::PlannerStatus::kExactSolution) << a.message;
  ASSERT_EQ(a.log.q.size(), b.log.q.size());
  for (std::size_t k = 0; k < a.log.q.size(); ++k) ASSERT_EQ(a.log.q[k], b.log.q[k]) << k;
  ASSERT_EQ(a.waypoints.size(), b.waypoints.size());
}

// A scan line that leaves the skin: one error naming the scene and the point.
// A budget too small for any path is the planner's status (OMPL's TIMEOUT), typed, with the scene
// in its message: `csp plan` reports "no plan" (exit 1) without reading the message.
TEST(TaskPath, NoPathWithinTheBudgetIsAStatus) {
  const Scene scene = load_scene(scene_file("mis_rcm"));
  const Model model = scene_model("panda", scene);
  planners::TaskPathOptions options;
  options.max_iterations = 1;
  const planners::TaskPath path = planners::plan_task_path(scene, model, options);
  EXPECT_EQ(path.status, planners::PlannerStatus::kNoSolution);
  EXPECT_NE(path.message.find(scene.name), std::string::npos) << path.message;
  EXPECT_NE(path.message.find("no path on the constraint manifold"), std::string::npos) << path.message;
  EXPECT_TRUE(path.log.t.empty());
}

TEST(TaskConstraint, ScanOffTheSkinNamesTheSceneAndThePoint) {
  Scene scene = load_scene(scene_file("ultrasound_abdomen"));
  std::get<UltrasoundScan>(scene.task).end.z() += 0.01;
  const Model model = scene_model("panda", scene);
  try {
    TaskConstraint task(model, scene);
    FAIL() << "no error";
  } catch (const planners::TaskError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ultrasound_abdomen.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("not on the skin of 'torso'"), std::string::npos) << what;
  }
}

// The rcm anchor of the vertical shaft (pivot 0 at mid insertion, by IK from the named pose) lands on
// the scene's port_hover: tip 0.10 above the port, shaft along -z, same branch.
TEST(TaskStates, RcmAnchorOfTheVerticalShaftMatchesPortHover) {
  const Scene scene = load_scene(scene_file("mis_rcm"));
  const Model model = scene_model("panda", scene);
  TaskConstraint task(model, scene);
  ClearanceChecker plain(model, scene);
  const Vector7& named = scene.pose("port_hover").q;
  planners::IkOptions options;
  options.tolerance = 1e-9;
  const planners::TcpTarget vertical = task.target(0.0);
  const planners::IkResult on_task = planners::solve_ik(planners::tcp_target_rows(model, vertical.position, vertical.axis), named,
                                                        model.parameters().joint_limits, nullptr, options);
  ASSERT_TRUE(on_task.converged);
  const Vector7 anchor = planners::task_anchor(task, on_task.q, plain);
  KdlPeer kdl(model);
  EXPECT_LT((kdl_tcp(kdl, anchor).translation - kdl_tcp(kdl, named).translation).norm(), 1e-6);
  EXPECT_LT((kdl_tcp(kdl, anchor).rotation.col(2) - kdl_tcp(kdl, named).rotation.col(2)).norm(), 1e-6);
  EXPECT_TRUE(planners::ik_branch(model, anchor) == planners::ik_branch(model, named));
  std::cout << "mis_rcm port_hover: anchor vs named pose, joint distance " << (anchor - named).norm() << " rad\n";
}

// A trocar moved (with the patient) out of the arm's reach: one error naming the scene and the state.
TEST(TaskStates, UnreachableTrocarNamesTheSceneAndTheState) {
  Scene scene = load_scene(scene_file("mis_rcm"));
  auto& rcm = std::get<RcmPivot>(scene.task);
  const Vector3 shift(0.0, 1.5, 0.0);
  rcm.trocar += shift;
  for (auto& o : scene.obstacles)
    if (auto* c = std::get_if<Capsule>(&o.shape)) {
      c->a += shift, c->b += shift;
    } else if (auto* s = std::get_if<Sphere>(&o.shape)) {
      s->center += shift;
    }
  const Model model = scene_model("panda", scene);
  TaskConstraint task(model, scene);
  ClearanceChecker contact(model, planners::contact_scene(scene, task.contact_obstacle()));
  ClearanceChecker plain(model, scene);
  try {
    planners::task_states(task, contact, plain);
    FAIL() << "no error";
  } catch (const planners::TaskError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mis_rcm.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("task start"), std::string::npos) << what;
    EXPECT_NE(what.find("unreachable"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace csp::test
