// The medical built-in controllers (docs/medical.md), written as a Franka user writes a torque
// controller on libfranka (Robot::control(torque_cb) with franka::Model): the robot adds gravity,
// the controller returns J^T F + Coriolis. Each follows its scene's task (csp/io/scene.hpp):
//   cartesian_impedance_force  ultrasound: impedance normal to the tool axis, force PI along it,
//                              along the scan line or the planner's task path (libfranka's
//                              cartesian_impedance_control and force_control examples combined)
//   rcm                        laparoscopy: tip impedance plus a spring keeping the shaft through the trocar
//   drilling                   burr hole: feed-rate advance along the burr axis, thrust limit,
//                              breakthrough detection
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/robot_state.hpp"

namespace csp::rt {

class JointLogReference;   // csp/rt/scenario.hpp: a joint log played in time

// Pose error of `pose` from (position_d, orientation_d) in the base frame, (position; rotation
// vector), as libfranka's cartesian_impedance_control example forms it: the orientation error is
// the quaternion difference's vector part rotated into the base frame (small-angle rotation vector / 2).
Vector6 pose_error(const Transform& pose, const Vector3& position_d, const Eigen::Quaterniond& orientation_d);

// A Cartesian impedance whose translational stiffness differs along a unit axis n and normal to
// it: K_t = k_normal (1 - n n^T) + k_axis n n^T, rotational k_rot 1; damping D likewise.
Matrix6 axis_split_gains(const Vector3& n, double normal, double axis, double rotational);

// Critical damping of a unit-mass spring per diagonal entry, as libfranka's example: D = 2 sqrt(K)
// (K is diagonal in the frame of axis_split_gains' axis, so the square root is taken there).
Matrix6 critical_damping(const Vector3& n, double normal, double axis, double rotational);

// The torque of a Cartesian wrench at a frame with base-frame Jacobian J, plus the Coriolis
// torque: tau = J^T F + c(q, dq) (gravity is the robot's).
Vector7 wrench_torque(const Matrix6x7& jacobian, const Vector6& wrench, const Vector7& coriolis);

// The point c of the line through `point` along unit `axis` nearest to `pivot`, and the lateral
// offset c - pivot (normal to the axis): the shaft's deviation from a remote centre of motion.
Vector3 line_offset_from(const Vector3& point, const Vector3& axis, const Vector3& pivot);

// The part of a joint torque that exerts no wrench at a frame with Jacobian J (full row rank):
// (1 - J^T (J^T)^+) tau, (J^T)^+ = (J J^T)^-1 J the Moore-Penrose pseudo-inverse of J^T. The
// null-space projector of franka_ros' cartesian_impedance_example_controller (a kinematic one: J of
// the projected torque is zero; Khatib's dynamically consistent projector would weight it by M^-1).
Vector7 null_space_torque(const Matrix6x7& jacobian, const Vector7& tau);

// The force PI along the tool axis (libfranka's force_control: feed-forward plus PI on the error,
// here on the force rather than on the joint torques): F = F_d + k_p (F_d - f) + k_i int (F_d - f) dt,
// the integral clamped to +-integral_limit (anti-windup while the probe is not yet in contact).
class AxisForcePI {
 public:
  AxisForcePI(double k_p, double k_i, double integral_limit) : k_p_(k_p), k_i_(k_i), limit_(integral_limit) {}
  double update(double desired, double measured, double dt);

 private:
  double k_p_, k_i_, limit_;
  double integral_ = 0.0;
};

// Breakthrough detection while drilling under force control (docs/medical.md): once the thrust
// has exceeded `engaged_thrust` (the bit is cutting bone), breakthrough is declared when the
// thrust drops below drop_ratio times its peak since engagement (the thrust-drop criterion of
// Ong & Bouazza-Marouf 1999 and Lee & Shih 2006), or when the feed velocity along the axis
// exceeds jump_ratio times the commanded feed rate (the bit lurches forward, same sources).
class BreakthroughDetector {
 public:
  struct Settings {
    double engaged_thrust = 8.0;   // [N]
    double drop_ratio = 0.5;
    double jump_ratio = 4.0;
  };
  explicit BreakthroughDetector(const Settings& settings) : settings_(settings) {}
  // Feeds one cycle's estimated thrust [N] and feed velocity [m/s] at feed rate [m/s]; true once
  // breakthrough was detected (it stays detected).
  bool update(double thrust, double feed_velocity, double feed_rate);
  bool detected() const { return detected_; }

 private:
  Settings settings_;
  double peak_ = 0.0;
  bool engaged_ = false, detected_ = false;
};

// The medical controllers' settings (scenario `controller:` keys, docs/medical.md).
struct MedicalControllerSpec {
  std::shared_ptr<const Scene> scene;   // the task: scan line, trocar, burr hole
  // cartesian_impedance_force
  double desired_force = 8.0;           // [N] the probe presses along the tool axis
  double force_k_p = 1.0, force_k_i = 2.0;   // libfranka force_control's k_p, k_i [1, 1/s]
  double force_integral_limit = 5.0;    // [N]
  double force_ramp = 1.0;              // [s] first-order ramp of the desired force (force_control's filter)
  double axis_damping = 100.0;          // [N s/m] along the tool axis
  double settle = 1.5;                  // [s] in contact before the scan starts
  // The planner's task path (`path:`, `csp plan task`'s trajectory.csv), played from `settle` on:
  // the forward kinematics of its joints is the scan's pose reference, its joints the posture the
  // null-space spring holds. Without it the scan follows the scene's straight line.
  std::shared_ptr<const JointLogReference> path;
  double null_space_stiffness = 50.0;   // [N m/rad] toward the path's joints, in the task's null space
  // rcm
  double insertion = 0.06;              // [m] tip depth below the trocar
  double insertion_time = 3.0;          // [s] from the start pose to the depth
  double pivot_amplitude = 0.2;         // [rad] about the base x axis through the trocar
  double pivot_frequency_hz = 0.2;
  double rcm_stiffness = 2000.0;        // [N/m] on the shaft's lateral offset at the trocar
  // drilling
  double feed_rate = 0.001;             // [m/s] (the scene's task speed unless given)
  double approach_speed = 0.01;         // [m/s] in free space down to the entry
  double axial_stiffness = 3000.0;      // [N/m]
  double max_thrust = 25.0;             // [N] the feed pauses above it
  bool breakthrough_detection = true;
  BreakthroughDetector::Settings breakthrough;
};

// What a medical controller found during its run (the metrics report it).
struct MedicalStatus {
  std::optional<double> breakthrough_detected_at;   // drilling: motion time [s]
};

// The law of a medical controller `type` (cartesian_impedance_force, rcm, drilling) with the
// start pose q0; `model` is the robot's own model (franka::Model), the translational and
// rotational stiffness those of its Cartesian impedance [N/m, N m/rad]. Call it with each
// RobotState, the motion time and the period [s]; it returns tau_J_d (without gravity).
using MedicalLaw = std::function<Vector7(const RobotState& state, double time, double period)>;
MedicalLaw make_medical_law(const std::string& type, const MedicalControllerSpec& spec, double translational_stiffness,
                            double rotational_stiffness, const Model& model, const Vector7& q0,
                            std::shared_ptr<MedicalStatus> status);

bool is_medical_controller(const std::string& type);

}  // namespace csp::rt
