#include "csp/rt/medical_plant.hpp"

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

BoneUnderBurr::BoneUnderBurr(const Scene& scene, const BoneLayerSettings& settings) : layer_(settings) {
  const auto* hole = std::get_if<BurrHole>(&scene.task);
  require(hole != nullptr, "a bone layer needs a scene whose task is a burr_hole (" + scene.path + ")");
  hole_ = *hole;
}

ToolForce BoneUnderBurr::force(double t, const Data& data, const Vector7& dq) {
  const double dt = last_time_ ? std::max(0.0, t - *last_time_) : 0.0;
  last_time_ = t;
  const Vector3& tip = data.O_T_EE.translation;
  const Vector3 inward = -hole_.axis;
  tip_depth_ = (tip - hole_.entry).dot(inward);
  thrust_ = layer_.step(tip_depth_, (point_jacobian(data, kNumJoints, tip) * dq).dot(inward), dt);
  if (layer_.broken_through() && !breakthrough_time_) breakthrough_time_ = t;
  const BoneLayerSettings& s = layer_.settings();
  // The face's stiffness while bone is left under the bit, the soft tissue's after.
  const double stiffness = layer_.broken_through() ? s.soft_stiffness : s.stiffness;
  return {tip, thrust_ * hole_.axis, tip_depth_ > 0.0 ? stiffness : 0.0};   // pushes the bit back out
}

TrocarRing::TrocarRing(const Scene& scene, const TrocarSettings& settings) : settings_(settings) {
  const auto* pivot = std::get_if<RcmPivot>(&scene.task);
  require(pivot != nullptr, "a trocar needs a scene whose task is an rcm_pivot (" + scene.path + ")");
  require(positive_finite(settings_.stiffness), "trocar stiffness: a positive number of N/m");
  require(non_negative_finite(settings_.damping), "trocar damping: a non-negative number of N s/m");
  require(settings_.port_axis.allFinite() && settings_.port_axis.norm() > 0.0, "trocar port_axis: a non-zero vector");
  settings_.port_axis.normalize();
  trocar_ = pivot->trocar;
}

ToolForce TrocarRing::force(double, const Data& data, const Vector7& dq) {
  // Where the shaft (flange to tip, along the tool's z axis) crosses the wall plane.
  const Vector3& a = settings_.port_axis;
  const Transform& tcp = data.O_T_EE;
  const Vector3 axis = tcp.rotation.col(2);
  const Vector3& flange = data.O_T_F.translation;
  const double along = axis.dot(a);
  offset_ = 0.0;
  if (std::abs(along) <= 1e-9) return {};   // the shaft lies in the wall's plane: it never crosses it
  const double s = (trocar_ - tcp.translation).dot(a) / along;   // from the tip along the axis
  const Vector3 crossing = tcp.translation + s * axis;
  const bool through = s < 0.0 && (crossing - tcp.translation).norm() < (flange - tcp.translation).norm();
  if (!through) return {};
  const Matrix3 in_wall = Matrix3::Identity() - a * a.transpose();
  const Vector3 offset = in_wall * (crossing - trocar_);
  offset_ = offset.norm();
  const Vector3 velocity = in_wall * (point_jacobian(data, kNumJoints, crossing) * dq);
  return {crossing, -settings_.stiffness * offset - settings_.damping * velocity, settings_.stiffness};
}

}  // namespace csp::rt
