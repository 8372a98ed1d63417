#include "csp/rt/medical_controllers.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "csp/dynamics/arrays.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::rt {

Vector6 pose_error(const Transform& pose, const Vector3& position_d, const Eigen::Quaterniond& orientation_d) {
  Vector6 error;
  error.head<3>() = pose.translation - position_d;
  Eigen::Quaterniond orientation(pose.rotation);
  if (orientation_d.coeffs().dot(orientation.coeffs()) < 0.0) orientation.coeffs() = -orientation.coeffs();
  const Eigen::Quaterniond difference(orientation.inverse() * orientation_d);
  error.tail<3>() = -pose.rotation * Vector3(difference.x(), difference.y(), difference.z());
  return error;
}

Matrix6 axis_split_gains(const Vector3& n, double normal, double axis, double rotational) {
  const Matrix3 along = n * n.transpose();
  Matrix6 gains = Matrix6::Zero();
  gains.topLeftCorner<3, 3>() = normal * (Matrix3::Identity() - along) + axis * along;
  gains.bottomRightCorner<3, 3>() = rotational * Matrix3::Identity();
  return gains;
}

Matrix6 critical_damping(const Vector3& n, double normal, double axis, double rotational) {
  return axis_split_gains(n, 2.0 * std::sqrt(normal), 2.0 * std::sqrt(axis), 2.0 * std::sqrt(rotational));
}

Vector7 wrench_torque(const Matrix6x7& jacobian, const Vector6& wrench, const Vector7& coriolis) {
  return jacobian.transpose() * wrench + coriolis;
}

Vector3 line_offset_from(const Vector3& point, const Vector3& axis, const Vector3& pivot) {
  const Vector3 nearest = point + (pivot - point).dot(axis) * axis;
  return nearest - pivot;
}

Vector7 null_space_torque(const Matrix6x7& jacobian, const Vector7& tau) {
  const Matrix6 JJt = jacobian * jacobian.transpose();
  return tau - jacobian.transpose() * JJt.ldlt().solve(jacobian * tau);
}

double AxisForcePI::update(double desired, double measured, double dt) {
  const double error = desired - measured;
  integral_ = std::clamp(integral_ + k_i_ * error * dt, -limit_, limit_);
  return desired + k_p_ * error + integral_;
}

bool BreakthroughDetector::update(double thrust, double feed_velocity, double feed_rate) {
  if (detected_) return true;
  if (thrust >= settings_.engaged_thrust) engaged_ = true;
  if (!engaged_) return false;
  peak_ = std::max(peak_, thrust);
  detected_ = thrust < settings_.drop_ratio * peak_ || feed_velocity > settings_.jump_ratio * feed_rate;
  return detected_;
}

namespace {

Vector3 force_of(const std::array<double, 6>& wrench) { return Vector3(wrench[0], wrench[1], wrench[2]); }

// What every medical law shares: the robot's model at the measured state, the TCP (libfranka's
// EE frame) pose, Jacobian and twist, the Coriolis torque, the force estimate tared at the start
// (libfranka's force_control subtracts its initial tau_ext the same way), and the torque-rate
// limit applied as franka::limitRate does (kMaxTorqueRate, from the last tau_J_d).
class ToolFrameLaw {
 public:
  ToolFrameLaw(const Model& model, const Vector7& q0) : model_(model) {
    forward_kinematics(model_, data_, q0);
    start_pose_ = frame_pose(data_, Frame::kEndEffector);
  }

  void measure(const RobotState& state) {
    q_ = from_array<Vector7>(state.q);
    dq_ = from_array<Vector7>(state.dq);
    forward_kinematics(model_, data_, q_);
    zero_jacobian(data_, Frame::kEndEffector, jacobian_);
    twist_ = jacobian_ * dq_;
    coriolis_torque(model_, data_, q_, dq_, coriolis_);
    if (!tared_) {
      force_tare_ = force_of(state.O_F_ext_hat_K);
      tared_ = true;
    }
    force_ = force_of(state.O_F_ext_hat_K) - force_tare_;
  }

  Vector7 limited(const Vector7& tau, const RobotState& state) const {
    const Vector7 last = from_array<Vector7>(state.tau_J_d);
    const Vector7 step = model_.parameters().joint_limits.dtau_max * kDeltaT * (1.0 - 1e-6);
    return last + (tau - last).cwiseMax(-step).cwiseMin(step);
  }

  const Vector7& q() const { return q_; }
  const Vector7& dq() const { return dq_; }
  const Model& model() const { return model_; }
  const Transform& pose() const { return frame_pose(data_, Frame::kEndEffector); }
  // The linear Jacobian of a point of the tool (base frame), by the robot's model.
  Matrix3x7 point_jacobian(const Vector3& point) const { return csp::point_jacobian(data_, kNumJoints, point); }
  const Transform& start_pose() const { return start_pose_; }
  const Matrix6x7& jacobian() const { return jacobian_; }
  const Vector6& twist() const { return twist_; }
  const Vector7& coriolis() const { return coriolis_; }
  // The estimated force the robot exerts on its environment (O_F_ext_hat_K's sign), tared.
  const Vector3& force() const { return force_; }

 private:
  Model model_;
  Data data_;
  Transform start_pose_;
  Vector7 q_, dq_, coriolis_;
  Matrix6x7 jacobian_;
  Vector6 twist_;
  Vector3 force_tare_ = Vector3::Zero(), force_ = Vector3::Zero();
  bool tared_ = false;
};

// Ultrasound: Cartesian impedance normal to the tool axis n along the scan, force PI along n.
// F = -K (x - x_d) - D (xdot - xdot_d) + n F_n,  K = k_t (1 - n n^T) + 0 n n^T (+ k_r on orientation),
// D = 2 sqrt(k_t) (1 - n n^T) + d_n n n^T,  F_n = AxisForcePI(F_d(t), n . F_ext_hat),
// tau = J^T F + c. The scan waits `settle` seconds (approach and force build-up) and then moves
// x_d from the task's start to its end at the task's speed: along the straight line, or along the
// planned path q_p(t - settle) with x_d its forward kinematics and a null-space spring toward q_p,
// tau += (1 - J^T (J^T)^+) (k_n (q_p - q) - 2 sqrt(k_n) dq).
class CartesianImpedanceForce {
 public:
  CartesianImpedanceForce(const MedicalControllerSpec& spec, double k_t, double k_r, const Model& model, const Vector7& q0)
      : spec_(spec), law_(model, q0), pi_(spec.force_k_p, spec.force_k_i, spec.force_integral_limit) {
    const auto* scan = std::get_if<UltrasoundScan>(&spec.scene->task);
    if (!scan) throw std::invalid_argument("cartesian_impedance_force needs a scene whose task is an ultrasound_scan");
    task_ = *scan;
    n_ = task_.tool_axis.normalized();
    orientation_d_ = Eigen::Quaterniond(law_.start_pose().rotation);
    stiffness_ = axis_split_gains(n_, k_t, 0.0, k_r);
    damping_ = critical_damping(n_, k_t, 0.0, k_r);
    damping_.topLeftCorner<3, 3>() += spec.axis_damping * n_ * n_.transpose();
  }

  Vector7 operator()(const RobotState& state, double time, double dt) {
    law_.measure(state);
    Vector3 position_d;
    Vector6 twist_d = Vector6::Zero();
    Vector7 tau_null = Vector7::Zero();
    if (spec_.path) {
      // Held at the path's first sample (at rest) while settling, then played.
      Vector7 q_p, dq_p, ddq_p;
      spec_.path->evaluate(Vector7::Zero(), std::max(0.0, time - spec_.settle), q_p, dq_p, ddq_p);
      forward_kinematics(law_.model(), path_data_, q_p);
      zero_jacobian(path_data_, Frame::kEndEffector, path_jacobian_);
      const Transform& pose_p = frame_pose(path_data_, Frame::kEndEffector);
      position_d = pose_p.translation;
      orientation_d_ = Eigen::Quaterniond(pose_p.rotation);
      twist_d = path_jacobian_ * dq_p;
      const double k_n = spec_.null_space_stiffness;
      tau_null = null_space_torque(law_.jacobian(), k_n * (q_p - law_.q()) - 2.0 * std::sqrt(k_n) * law_.dq());
    } else {
      const Vector3 line = task_.end - task_.start;
      const double length = line.norm();
      const double travelled = std::clamp(task_.speed * (time - spec_.settle), 0.0, length);
      if (travelled > 0.0 && travelled < length) twist_d.head<3>() = task_.speed * line / length;
      position_d = task_.start + (length > 0.0 ? travelled / length : 0.0) * line;
    }
    const double force_d = spec_.desired_force * (1.0 - std::exp(-time / spec_.force_ramp));
    const double force_n = pi_.update(force_d, n_.dot(law_.force()), dt);
    Vector6 wrench = -stiffness_ * pose_error(law_.pose(), position_d, orientation_d_) - damping_ * (law_.twist() - twist_d);
    wrench.head<3>() += force_n * n_;
    return law_.limited(wrench_torque(law_.jacobian(), wrench, law_.coriolis()) + tau_null, state);
  }

 private:
  MedicalControllerSpec spec_;
  ToolFrameLaw law_;
  Data path_data_;   // the robot's model at the path's joints (the reference's own workspace)
  Matrix6x7 path_jacobian_;
  AxisForcePI pi_;
  UltrasoundScan task_;
  Vector3 n_;
  Eigen::Quaterniond orientation_d_;
  Matrix6 stiffness_, damping_;
};

// Laparoscopy: the tip follows p_d = trocar + s(t) u(t), the shaft direction u(t) the start's
// rotated by theta(t) about the base x axis through the trocar (the pivot), s(t) a quintic from
// the start depth to `insertion`; a Cartesian impedance on that pose, plus an RCM spring on the
// shaft point c nearest the trocar once the shaft is through it:
// tau = J^T(-K e - D (xdot - xdot_d)) + J_c^T(-k_rcm e_c - d_rcm (1 - u u^T) J_c dq) + c(q, dq),
// e_c = c - trocar (normal to the shaft), J_c the shaft point's linear Jacobian.
class RcmController {
 public:
  RcmController(const MedicalControllerSpec& spec, double k_t, double k_r, const Model& model, const Vector7& q0)
      : spec_(spec), law_(model, q0) {
    const auto* pivot = std::get_if<RcmPivot>(&spec.scene->task);
    if (!pivot) throw std::invalid_argument("rcm needs a scene whose task is an rcm_pivot");
    trocar_ = pivot->trocar;
    start_rotation_ = law_.start_pose().rotation;
    const Vector3 u0 = start_rotation_.col(2);
    start_depth_ = (law_.start_pose().translation - trocar_).dot(u0);
    stiffness_ = axis_split_gains(u0, k_t, k_t, k_r);
    damping_ = critical_damping(u0, k_t, k_t, k_r);
    shaft_length_ = model.parameters().F_T_EE.translation.norm();
  }

  Vector7 operator()(const RobotState& state, double time) {
    law_.measure(state);
    double r, dr, ddr;
    quintic_ramp(time, spec_.insertion_time, r, dr, ddr);
    const double depth = start_depth_ + r * (spec_.insertion - start_depth_);
    const double ddepth = dr * (spec_.insertion - start_depth_);
    // The pivot: a sine ramped in over one second after the insertion.
    const double tau = std::max(0.0, time - spec_.insertion_time);
    double p, dp, ddp;
    quintic_ramp(tau, 1.0, p, dp, ddp);
    const double w = 2.0 * M_PI * spec_.pivot_frequency_hz;
    const double theta = p * spec_.pivot_amplitude * std::sin(w * tau);
    const double dtheta = spec_.pivot_amplitude * (dp * std::sin(w * tau) + p * w * std::cos(w * tau));
    const Matrix3 rotation_d = Eigen::AngleAxisd(theta, Vector3::UnitX()).toRotationMatrix() * start_rotation_;
    const Vector3 u = rotation_d.col(2);
    const Vector3 omega = dtheta * Vector3::UnitX();
    Vector6 twist_d;
    twist_d << ddepth * u + depth * omega.cross(u), omega;

    const Vector6 error = pose_error(law_.pose(), trocar_ + depth * u, Eigen::Quaterniond(rotation_d));
    const Vector6 wrench = -stiffness_ * error - damping_ * (law_.twist() - twist_d);
    Vector7 tau_cmd = wrench_torque(law_.jacobian(), wrench, law_.coriolis());

    // The RCM spring, only while the trocar lies along the shaft.
    const Vector3 tip = law_.pose().translation, axis = law_.pose().rotation.col(2);
    const double inserted = (tip - trocar_).dot(axis);
    if (inserted > 0.0 && inserted < shaft_length_) {
      const Vector3 offset = line_offset_from(tip, axis, trocar_);
      const Matrix3x7 shaft_point = law_.point_jacobian(trocar_ + offset);
      const Matrix3 lateral = Matrix3::Identity() - axis * axis.transpose();
      const Vector3 force = -spec_.rcm_stiffness * offset -
                            2.0 * std::sqrt(spec_.rcm_stiffness) * lateral * (shaft_point * from_array<Vector7>(state.dq));
      tau_cmd += shaft_point.transpose() * force;
    }
    return law_.limited(tau_cmd, state);
  }

 private:
  MedicalControllerSpec spec_;
  ToolFrameLaw law_;
  Vector3 trocar_;
  Matrix3 start_rotation_;
  double start_depth_ = 0.0, shaft_length_ = 0.0;
  Matrix6 stiffness_, damping_;
};

// Burr hole: the tip's depth x along n = -axis below the entry follows x_d, which moves at
// approach_speed to kFeedStart above the entry, then at the feed rate to `advance` below the entry
// (the scene's advance counts from the entry: docs/medical.md), pausing while the estimated
// thrust exceeds max_thrust. Axial stiffness k_a, lateral and orientation impedance hold the axis.
// On detected breakthrough, x_d relaxes to where the tip is (20 ms time constant: the torque
// rate limit) and stays.
class DrillingController {
 public:
  static constexpr double kFeedStart = 0.002;       // [m] above the entry: the feed rate from here on
  static constexpr double kStopTimeConstant = 0.02;  // [s]

  DrillingController(const MedicalControllerSpec& spec, double k_t, double k_r, const Model& model, const Vector7& q0,
                     std::shared_ptr<MedicalStatus> status)
      : spec_(spec), law_(model, q0), detector_(spec.breakthrough), status_(std::move(status)) {
    const auto* hole = std::get_if<BurrHole>(&spec.scene->task);
    if (!hole) throw std::invalid_argument("drilling needs a scene whose task is a burr_hole");
    hole_ = *hole;
    n_ = -hole_.axis.normalized();
    orientation_d_ = Eigen::Quaterniond(law_.start_pose().rotation);
    depth_d_ = depth(law_.start_pose().translation);
    stiffness_ = axis_split_gains(n_, k_t, spec.axial_stiffness, k_r);
    damping_ = critical_damping(n_, k_t, spec.axial_stiffness, k_r);
  }

  Vector7 operator()(const RobotState& state, double time, double dt) {
    law_.measure(state);
    const double x = depth(law_.pose().translation);
    const double thrust = n_.dot(law_.force());
    const double feed_velocity = n_.dot(law_.twist().head<3>());
    double speed = 0.0;
    if (!stopped_) {
      const bool feeding = depth_d_ >= -kFeedStart;
      speed = feeding ? spec_.feed_rate : spec_.approach_speed;
      if (thrust > spec_.max_thrust) speed = 0.0;
      if (depth_d_ >= hole_.advance) speed = 0.0;
      depth_d_ = std::min(depth_d_ + speed * dt, feeding ? hole_.advance : -kFeedStart);
      if (spec_.breakthrough_detection && feeding && detector_.update(thrust, feed_velocity, spec_.feed_rate)) {
        stopped_ = true;
        hold_ = x;
        status_->breakthrough_detected_at = time;
      }
    }
    if (stopped_) depth_d_ += (hold_ - depth_d_) * std::min(1.0, dt / kStopTimeConstant);
    Vector6 twist_d = Vector6::Zero();
    twist_d.head<3>() = speed * n_;
    const Vector6 error = pose_error(law_.pose(), hole_.entry + depth_d_ * n_, orientation_d_);
    const Vector6 wrench = -stiffness_ * error - damping_ * (law_.twist() - twist_d);
    return law_.limited(wrench_torque(law_.jacobian(), wrench, law_.coriolis()), state);
  }

 private:
  double depth(const Vector3& tip) const { return (tip - hole_.entry).dot(n_); }

  MedicalControllerSpec spec_;
  ToolFrameLaw law_;
  BreakthroughDetector detector_;
  std::shared_ptr<MedicalStatus> status_;
  BurrHole hole_;
  Vector3 n_;
  Eigen::Quaterniond orientation_d_;
  Matrix6 stiffness_, damping_;
  double depth_d_ = 0.0, hold_ = 0.0;
  bool stopped_ = false;
};

}  // namespace

bool is_medical_controller(const std::string& type) {
  return type == "cartesian_impedance_force" || type == "rcm" || type == "drilling";
}

MedicalLaw make_medical_law(const std::string& type, const MedicalControllerSpec& spec, double translational_stiffness,
                            double rotational_stiffness, const Model& model, const Vector7& q0,
                            std::shared_ptr<MedicalStatus> status) {
  if (!spec.scene) throw std::invalid_argument(type + " needs the scenario's scene (its task)");
  const double k_t = translational_stiffness, k_r = rotational_stiffness;
  if (type == "cartesian_impedance_force") {
    auto law = std::make_shared<CartesianImpedanceForce>(spec, k_t, k_r, model, q0);
    return [law](const RobotState& s, double t, double dt) { return (*law)(s, t, dt); };
  }
  if (type == "rcm") {
    auto law = std::make_shared<RcmController>(spec, k_t, k_r, model, q0);
    return [law](const RobotState& s, double t, double) { return (*law)(s, t); };
  }
  if (type == "drilling") {
    auto law = std::make_shared<DrillingController>(spec, k_t, k_r, model, q0, std::move(status));
    return [law](const RobotState& s, double t, double dt) { return (*law)(s, t, dt); };
  }
  throw std::invalid_argument("unknown medical controller `" + type + "`");
}

}  // namespace csp::rt
