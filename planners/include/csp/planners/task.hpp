// The medical task's own path (docs/planning-task-paths.md): its equality constraint on the arm
// with an analytic Jacobian, the task's start, end and excitation anchors by inverse kinematics,
// the path planned on the constraint manifold by OMPL (planners/ompl_bridge), densified, projected
// back onto the manifold and timed along the task, sampled at 1 kHz as a joint log.
//
// Constraints (F: the TCP frame, origin p, axes x, y, z; all in the base frame):
//   ultrasound_scan  codim 4: |p - c(p)| - r = 0 (TCP on the skin, c the closest point of the skin
//                    solid's core), x.n = y.n = 0 (probe axis along the skin normal n), m.(p - start)
//                    = 0 (TCP in the scan plane spanned by the scan line and the normal)
//   rcm_pivot        codim 2: [x^T; y^T](p_rcm - p) = 0 (the shaft line through the trocar point)
//   burr_hole        codim 4: u1.(p - e) = u2.(p - e) = 0 (TCP on the burr axis), x.a = y.a = 0
//                    (drill along the axis); u1, u2, a orthonormal
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/ik.hpp"
#include "csp/planners/planner_status.hpp"

namespace csp::planners {

// A task that cannot be done as asked (unreachable, in collision, no path in the budget): the
// message names the scene and what failed.
class TaskError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A TCP target: position and the unit direction of the tool's z axis.
struct TcpTarget {
  Vector3 position = Vector3::Zero();
  Vector3 axis = -Vector3::UnitZ();
};

class TaskConstraint {
 public:
  // The scene's task on `model` (whose end effector is the scene's TCP, see with_tool). Throws
  // TaskError naming the scene when the task's geometry does not fit it (e.g. a scan start that is
  // not on a capsule or sphere of the patient, a tool axis that is not the skin's inward normal).
  TaskConstraint(const Model& model, const Scene& scene);

  int codim() const { return codim_; }
  // f(q) (codim rows) and its analytic Jacobian df/dq (codim x 7).
  void evaluate(const Vector7& q, Eigen::VectorXd& f, Eigen::MatrixXd& jacobian);
  Eigen::VectorXd function(const Vector7& q);
  ConstraintRows rows();   // evaluate() as IK rows (refers to this object)

  // The task coordinate the path is timed along: scan: distance of the TCP along the scan line from
  // its start [m]; rcm: the shaft's pivot angle in the sweep plane (y-z) [rad]; burr: the TCP's
  // height above the entry along the axis [m].
  double progress(const Vector7& q);
  // Its values at the task's start and end.
  double progress_start() const { return progress_start_; }
  double progress_end() const { return progress_end_; }
  // The TCP target at a progress value (on the manifold).
  TcpTarget target(double progress) const;
  // The excitation anchor's TCP target at a progress value: the contact point (scan: the TCP on the
  // skin; rcm: the trocar; burr: the entry) retracted along the tool axis by anchor_retract(), same
  // axis. ultrasound and rcm: the task's `hover`; burr: the patient clearance + 0.01 m (as the
  // scene's burr_hover: the bit clears the skull by its class clearance, strictly).
  TcpTarget anchor_target(double progress) const;
  // The same for any configuration on the manifold, along its own tool axis.
  TcpTarget anchor_target(const Vector7& q);
  double anchor_retract() const { return anchor_retract_; }

  // True when the state respects the task's inequalities (rcm: insertion within its range, pivot
  // within max_pivot from the vertical); the others have none.
  bool within_ranges(const Vector7& q);

  // The obstacle the tool touches by design (skin under the probe, the torso at the port, the skull):
  // the tool's capsules are exempt from it during the task; the arm's links are not.
  const std::string& contact_obstacle() const { return contact_obstacle_; }

  const Scene& scene() const { return scene_; }
  const Model& model() const { return model_; }

 private:
  void kinematics(const Vector7& q);

  Model model_;
  Data data_;
  Scene scene_;
  int codim_ = 0;
  std::string contact_obstacle_;
  double progress_start_ = 0.0, progress_end_ = 0.0, anchor_retract_ = 0.0;
  // scan: the skin solid's core (segment a-b, or a point when a == b) and radius, the line, the plane
  Vector3 skin_a_ = Vector3::Zero(), skin_b_ = Vector3::Zero();
  double skin_radius_ = 0.0;
  Vector3 line_start_ = Vector3::Zero(), line_direction_ = Vector3::Zero(), plane_normal_ = Vector3::Zero();
  // rcm / burr
  Vector3 point_ = Vector3::Zero(), axis_ = Vector3::Zero(), u1_ = Vector3::Zero(), u2_ = Vector3::Zero();
  double insertion_ = 0.0;   // rcm: tip depth below the trocar along the sweep [m]
  Matrix6x7 jacobian_ = Matrix6x7::Zero();
};

// The scene the task's states are checked in: every patient solid keeps its clearance against the
// arm's links; the tool's capsules see a copy of it (class "task_contact", clearance 0: touching,
// no penetration), and the tool's tip capsule (the one ending at the TCP) is exempt from the
// contact obstacle (the probe's face on the skin, the shaft through the port, the bit at the bone).
Scene contact_scene(const Scene& scene, const std::string& contact_obstacle);

struct TaskPathOptions {
  unsigned seed = 1;
  int max_iterations = 20000;          // RRTConnect iterations (deterministic cap)
  double joint_margin = 0.5;           // the planner's joint bounds: the task's start and end +- this [rad]
  double range = 0.3;                  // RRTConnect's step [rad]: each step is cut into delta-long projected steps
  int simplify_steps = 20;             // shortcut attempts (each a geodesic of projected steps)
  double delta = 0.01;                 // step on the manifold and max joint step of the dense path [rad]
  double tolerance = 1e-6;             // constraint tolerance of the projection (|f|) [m]
  bool analytic_jacobian = true;       // false: OMPL's numerical Jacobian (the benchmark's baseline)
  double velocity_fraction = 0.5;      // of the model's dq_max, ddq_max, dddq_max
  double acceleration_fraction = 0.5;
  double jerk_fraction = 0.5;
  double tool_speed = 0.02;            // TCP speed cap of the segments the task gives no speed (rcm sweep, drill approach) [m/s]
  double rate_hz = 1000.0;
};

struct TaskPath {
  // kNoSolution: no path on the constraint manifold within max_iterations (`message` says so); the
  // fields below the planner's are then empty.
  PlannerStatus status = PlannerStatus::kNoSolution;
  std::string message;
  std::string scene;
  int codim = 0;
  Vector7 start = Vector7::Zero(), end = Vector7::Zero();   // task start and end (IK)
  std::vector<Vector7> anchors;       // hover configurations: start and end retracted (one if they coincide)
  std::vector<Vector7> waypoints;     // the planner's path on the manifold
  std::vector<Vector7> states;        // densified (<= delta/2 per joint) and projected: the task's configurations
  std::vector<double> progress;       // task coordinate per state
  JointLog log;                       // timed, rest to rest, sampled at rate_hz
  double duration = 0.0;              // [s]
  int iterations = 0;                 // planner iterations
  double planning_seconds = 0.0;
};

// The start/end states and the anchors of the task by IK, seeded from the scene's named poses.
// Throws TaskError naming the scene and the state that failed.
struct TaskStates {
  Vector7 start = Vector7::Zero(), end = Vector7::Zero();
  std::vector<Vector7> anchors;
};
TaskStates task_states(TaskConstraint& task, ClearanceChecker& contact_checker, ClearanceChecker& scene_checker);

// The anchor of a task configuration q_task (e.g. any of TaskPath::states): anchor_target(q_task)
// by IK seeded at q_task (same branch), collision-free in the scene itself (no contact exemption).
// Throws TaskError naming the scene if unreachable, in collision or on another branch.
Vector7 task_anchor(TaskConstraint& task, const Vector7& q_task, ClearanceChecker& scene_checker);

// The whole task path: states, planning on the manifold, densification, timing, 1 kHz log.
// `model` carries the scene's tool (with_tool). Throws TaskError naming the scene and what failed
// when the task cannot be asked (unreachable, in collision); no path within the budget is a status.
TaskPath plan_task_path(const Scene& scene, const Model& model, const TaskPathOptions& options = {});

}  // namespace csp::planners
