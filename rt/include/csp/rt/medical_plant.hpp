// The tissue the medical tools work in, as part of the emulated plant (docs/medical.md): the bone
// a burr drills through (a thrust / feed-rate removal law over a bone layer on soft tissue) and
// the trocar's compliant ring in the abdominal wall. Each is a ContactElement of the scene's
// contact engine (rt/contact.hpp): evaluated in every substep on the arm the engine has placed,
// its force applied to the tool as any contact's, so the plant feels it and the robot only
// estimates it through tau_J.
#pragma once

#include <optional>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/contact.hpp"

namespace csp::rt {

// The bone layer under the burr, along the burr axis (depth x below the entry, positive inward).
// Numbers: docs/medical.md gives each its source or marks it an assumption.
struct BoneLayerSettings {
  double thickness = 0.006;          // [m] cranial vault
  double stiffness = 2.0e5;          // [N/m] of the uncut bone face under the bit's point
  double dissipation = 0.5;          // [s/m] Hunt-Crossley alpha: f = k d (1 + alpha d_dot), never pulling
  double threshold_thrust = 5.0;     // [N] below it the burr does not cut
  double removal_rate = 1.0e-4;      // [m/s per N] feed rate per newton of thrust above the threshold
  double point_height = 0.00105;     // [m] of the bit's conical point: the thrust fades over it at exit
  double soft_stiffness = 200.0;     // [N/m] dura and brain under the bone
};

// The law along the axis: the uncut face sits at the removed depth r (0 at the entry). With the
// tip at x and indentation d = x - r > 0 the face pushes back with f = k d (1 + alpha x_dot)
// (>= 0; Hunt-Crossley with n = 1) and recedes at r_dot = c max(0, f - f_0) while r < T. Once less
// than the point height h of bone is left the point exits: the thrust felt is f (T - r) / h while
// the engaged part still cuts at f's rate (the thrust drop before breakthrough of Lee & Shih
// 2006). Past the layer (r = T) the soft tissue pushes with k_s (x - T).
class BoneLayer {
 public:
  explicit BoneLayer(const BoneLayerSettings& settings);   // std::invalid_argument on a bad number
  // The thrust on the bit [N, >= 0] at depth x [m] moving at x_dot [m/s]; removes bone over dt [s].
  double step(double x, double x_dot, double dt);
  double removed() const { return removed_; }
  bool broken_through() const { return removed_ >= settings_.thickness; }
  const BoneLayerSettings& settings() const { return settings_; }

 private:
  BoneLayerSettings settings_;
  double removed_ = 0.0;
};

// The trocar: a compliant ring in the abdominal wall (the plane through the trocar normal to the
// port axis) pushing the shaft back toward the port axis, F = -k e - d e_dot, e the shaft's
// crossing of the wall from the trocar point (in the plane).
struct TrocarSettings {
  double stiffness = 1000.0;   // [N/m]
  double damping = 10.0;       // [N s/m]
  Vector3 port_axis = Vector3::UnitZ();   // the wall's normal at the trocar, unit
};

// The bone layer under the scene's burr hole (a burr_hole task), felt by the bit's tip (the TCP)
// along the burr axis.
class BoneUnderBurr final : public ContactElement {
 public:
  // std::invalid_argument if the scene's task is no burr hole or a setting is out of range.
  BoneUnderBurr(const Scene& scene, const BoneLayerSettings& settings);
  // Integrates the bone removal from the last call's time.
  ToolForce force(double t, const Data& data, const Vector7& dq) override;

  const BoneLayer& layer() const { return layer_; }
  double thrust() const { return thrust_; }           // at the last call, along the burr axis, outward [N]
  double tip_depth() const { return tip_depth_; }     // below the burr entry [m]
  std::optional<double> breakthrough_time() const { return breakthrough_time_; }

 private:
  BoneLayer layer_;
  BurrHole hole_;
  std::optional<double> last_time_, breakthrough_time_;
  double thrust_ = 0.0, tip_depth_ = 0.0;
};

// The trocar's ring at the scene's port (an rcm_pivot task), on the shaft (the tool's z axis from
// the flange to the tip) where it crosses the wall.
class TrocarRing final : public ContactElement {
 public:
  // std::invalid_argument if the scene's task is no RCM pivot or a setting is out of range.
  TrocarRing(const Scene& scene, const TrocarSettings& settings);
  ToolForce force(double t, const Data& data, const Vector7& dq) override;

  // The shaft's distance from the port axis in the wall at the last call [m] (0: not through it).
  double offset() const { return offset_; }

 private:
  TrocarSettings settings_;
  Vector3 trocar_ = Vector3::Zero();
  double offset_ = 0.0;
};

}  // namespace csp::rt
