#include "csp/dynamics/algorithms.hpp"
#include "steps.hpp"

namespace csp {
namespace {

using LinkVectors = std::array<Vector3, kNumJoints>;

// Inward: each link passes its wrench to its parent (Craig eqs. 6.51-6.53); tau_i is the z moment.
void inward_pass(const Model& model, const Data& data, const LinkVectors& force, const LinkVectors& moment,
                 Vector7& tau) {
  Vector3 f = Vector3::Zero(), n = Vector3::Zero();
  for (int i = kNumJoints - 1; i >= 0; --i) {
    if (i + 1 < kNumJoints) {
      const JointGeometry& child = model.joint(i + 1);
      const double c = data.cos_theta[i + 1], s = data.sin_theta[i + 1];
      const Vector3 f_child = child.rotate(c, s, f);
      n = child.rotate(c, s, n) + child.origin.cross(f_child);
      f = f_child;
    }
    f += force[i];
    n += moment[i];
    tau[i] = n.z();
  }
}

// Recursive Newton-Euler in link frames (Craig, ch. 6.5; seed paper eqs. 5-9), with the body
// inertia taken about the link origin so that the CoM terms fold into one spatial product.
void newton_euler(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq,
                  const Vector3& gravity, const LinkWrenches& f_ext, Vector7& tau) {
  const Vector3 z = Vector3::UnitZ();
  LinkVectors force, moment;

  detail::update_joint_angles(model, data, q);

  // Outward: velocities and accelerations of each link origin, in its own frame.
  Vector3 w = Vector3::Zero(), dw = Vector3::Zero();
  Vector3 dv = -gravity;   // a base accelerating upwards stands in for gravity (Craig sec. 6.5)
  for (int i = 0; i < kNumJoints; ++i) {
    const JointGeometry& joint = model.joint(i);
    const double c = data.cos_theta[i], s = data.sin_theta[i];
    const Vector3& p = joint.origin;
    const Vector3 dv_parent_at_origin = dw.cross(p) + w.cross(w.cross(p)) + dv;
    const Vector3 w_parent = joint.rotate_back(c, s, w);
    w = w_parent + dq[i] * z;                                                // eq. 6.45
    dw = joint.rotate_back(c, s, dw) + w_parent.cross(dq[i] * z) + ddq[i] * z;  // eq. 6.46
    dv = joint.rotate_back(c, s, dv_parent_at_origin);                        // eq. 6.47

    // Net force and moment about the origin (eqs. 6.48-6.50 with h = m c, I_O = I_C - m [c]x^2).
    const SpatialInertia& I = model.body(i);
    const Vector3 Iw = I.rotational * w;
    force[i] = I.mass * dv + dw.cross(I.first_moment) + w.cross(w.cross(I.first_moment)) - f_ext[i].head<3>();
    moment[i] = I.rotational * dw + w.cross(Iw) + I.first_moment.cross(dv) - f_ext[i].tail<3>();
  }

  inward_pass(model, data, force, moment, tau);
}

}  // namespace

void rnea(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq,
          const LinkWrenches& f_ext, Vector7& tau) {
  newton_euler(model, data, q, dq, ddq, model.gravity(), f_ext, tau);
  // Each rotor, spinning about its joint axis, needs I_a,i ddq_i more (Featherstone sec. 7.3).
  tau += model.armature().cwiseProduct(ddq);
}

void rnea(const Model& model, Data& data, const Vector7& q, const Vector7& dq, const Vector7& ddq, Vector7& tau) {
  rnea(model, data, q, dq, ddq, kNoLinkWrenches, tau);
}

// At rest only gravity acts (w = dw = 0): each link's net wrench is its weight, m dv and h x dv.
void gravity_torque(const Model& model, Data& data, const Vector7& q, Vector7& g) {
  detail::update_joint_angles(model, data, q);
  LinkVectors force, moment;
  Vector3 dv = -model.gravity();
  for (int i = 0; i < kNumJoints; ++i) {
    dv = model.joint(i).rotate_back(data.cos_theta[i], data.sin_theta[i], dv);
    const SpatialInertia& I = model.body(i);
    force[i] = I.mass * dv;
    moment[i] = I.first_moment.cross(dv);
  }
  inward_pass(model, data, force, moment, g);
}

void coriolis_torque(const Model& model, Data& data, const Vector7& q, const Vector7& dq, Vector7& c) {
  newton_euler(model, data, q, dq, Vector7::Zero(), Vector3::Zero(), kNoLinkWrenches, c);
}

}  // namespace csp
