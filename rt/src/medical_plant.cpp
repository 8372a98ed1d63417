#include "csp/rt/medical_plant.hpp"

#include "csp/rt/medical_controllers.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace csp::rt {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative_finite(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

BoneLayer::BoneLayer(const BoneLayerSettings& s) : settings_(s) {
  require(positive_finite(s.thickness), "bone thickness: a positive number of metres");
  require(positive_finite(s.stiffness), "bone stiffness: a positive number of N/m");
  require(non_negative_finite(s.dissipation), "bone dissipation: a non-negative number of s/m");
  require(non_negative_finite(s.threshold_thrust), "bone threshold_thrust: a non-negative number of N");
  require(positive_finite(s.removal_rate), "bone removal_rate: a positive number of m/s per N");
  require(positive_finite(s.point_height), "bone point_height: a positive number of metres");
  require(non_negative_finite(s.soft_stiffness), "bone soft_stiffness: a non-negative number of N/m");
}

double BoneLayer::step(double x, double x_dot, double dt) {
  const BoneLayerSettings& s = settings_;
  if (broken_through()) return x > s.thickness ? s.soft_stiffness * (x - s.thickness) : 0.0;
  const double indentation = x - removed_;
  if (indentation <= 0.0) return 0.0;
  const double left = s.thickness - removed_;
  const double engaged = std::min(1.0, left / s.point_height);
  // The face's push as if the whole point were engaged; the cut rate follows it (the engaged part
  // cuts at the same pressure), the thrust only the engaged fraction of it.
  const double full = std::max(0.0, s.stiffness * indentation * (1.0 + s.dissipation * x_dot));
  removed_ = std::min(s.thickness, removed_ + dt * s.removal_rate * std::max(0.0, full - s.threshold_thrust));
  return engaged * full;
}

MedicalPlant::MedicalPlant(const ModelParameters& plant, const Scene& scene, const MedicalPlantSettings& settings)
    : model_(plant), trocar_(settings.trocar) {
  if (settings.bone) {
    const auto* hole = std::get_if<BurrHole>(&scene.task);
    require(hole != nullptr, "a bone layer needs a scene whose task is a burr_hole (" + scene.path + ")");
    hole_ = *hole;
    bone_.emplace(*settings.bone);
  }
  if (trocar_) {
    const auto* pivot = std::get_if<RcmPivot>(&scene.task);
    require(pivot != nullptr, "a trocar needs a scene whose task is an rcm_pivot (" + scene.path + ")");
    require(positive_finite(trocar_->stiffness), "trocar stiffness: a positive number of N/m");
    require(non_negative_finite(trocar_->damping), "trocar damping: a non-negative number of N s/m");
    require(trocar_->port_axis.allFinite() && trocar_->port_axis.norm() > 0.0, "trocar port_axis: a non-zero vector");
    trocar_->port_axis.normalize();
    trocar_point_ = pivot->trocar;
  }
}

Vector7 MedicalPlant::joint_torque(double t, const Vector7& q, const Vector7& dq) {
  const double dt = last_time_ ? std::max(0.0, t - *last_time_) : 0.0;
  last_time_ = t;
  forward_kinematics(model_, data_, q);
  zero_jacobian(data_, Frame::kEndEffector, jacobian_);
  const Transform& tcp = frame_pose(data_, Frame::kEndEffector);
  Vector7 tau = Vector7::Zero();   // J^T F of the forces on the tool
  force_.setZero();

  if (bone_) {
    const Vector3 n = -hole_.axis;
    const Vector3 tip_velocity = jacobian_.topRows<3>() * dq;
    tip_depth_ = (tcp.translation - hole_.entry).dot(n);
    thrust_ = bone_->step(tip_depth_, tip_velocity.dot(n), dt);
    if (bone_->broken_through() && !breakthrough_time_) breakthrough_time_ = t;
    const Vector3 force = thrust_ * hole_.axis;   // pushes the bit back out
    tau += jacobian_.topRows<3>().transpose() * force;
    force_ += force;
  }

  if (trocar_) {
    // Where the shaft (flange to tip, along the tool's z axis) crosses the wall plane.
    const Vector3& a = trocar_->port_axis;
    const Vector3 axis = tcp.rotation.col(2);
    const Vector3 flange = frame_pose(data_, Frame::kFlange).translation;
    const double along = axis.dot(a);
    trocar_offset_ = 0.0;
    if (std::abs(along) > 1e-9) {
      const double s = (trocar_point_ - tcp.translation).dot(a) / along;   // from the tip along the axis
      const Vector3 crossing = tcp.translation + s * axis;
      const bool through = s < 0.0 && (crossing - tcp.translation).norm() < (flange - tcp.translation).norm();
      if (through) {
        const Matrix3 in_wall = Matrix3::Identity() - a * a.transpose();
        const Vector3 offset = in_wall * (crossing - trocar_point_);
        trocar_offset_ = offset.norm();
        const Eigen::Matrix<double, 3, 7> J = point_jacobian(jacobian_, crossing - tcp.translation);
        const Vector3 force = -trocar_->stiffness * offset - trocar_->damping * (in_wall * (J * dq));
        tau += J.transpose() * force;
        force_ += force;
      }
    }
  }
  return -tau;
}

}  // namespace csp::rt
