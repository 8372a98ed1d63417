// RNEA and the inertial regressor over many states (batch.hpp): the Newton-Euler recursion of
// rnea.cpp and regressor.cpp on four states at once, every scalar a lane of Eigen::Array4d (one
// AVX2 register). The equations are theirs: outward Craig eqs. 6.45-6.47, each link's wrench about
// its origin eqs. 6.48-6.50, inward eqs. 6.51-6.53; for the regressor each link's wrench as its
// 6x10 regressor in the standard parameters (Atkeson, An and Hollerbach 1986), carried inward
// column by column.
#include "csp/dynamics/batch.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "batch_trig.hpp"

namespace csp {
namespace {

constexpr int kLanes = 4;   // doubles in one AVX2 register: four states per instruction
using Lane = Eigen::Array<double, kLanes, 1>;

// A 3-vector of each of four states.
struct LaneVector {
  Lane x = Lane::Zero(), y = Lane::Zero(), z = Lane::Zero();
};

LaneVector broadcast(const Vector3& v) { return {Lane::Constant(v.x()), Lane::Constant(v.y()), Lane::Constant(v.z())}; }
LaneVector operator+(const LaneVector& a, const LaneVector& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
LaneVector operator-(const LaneVector& a) { return {-a.x, -a.y, -a.z}; }
LaneVector operator*(const Lane& s, const LaneVector& v) { return {s * v.x, s * v.y, s * v.z}; }

LaneVector cross(const LaneVector& a, const LaneVector& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// I v with the same matrix I for the four states.
LaneVector times(const Matrix3& I, const LaneVector& v) {
  return {I(0, 0) * v.x + I(0, 1) * v.y + I(0, 2) * v.z,  //
          I(1, 0) * v.x + I(1, 1) * v.y + I(1, 2) * v.z,  //
          I(2, 0) * v.x + I(2, 1) * v.y + I(2, 2) * v.z};
}

// One joint of four states: cos and sin of theta = q + theta_offset, dq, ddq.
struct LaneJoint {
  Lane cos_theta, sin_theta, dq, ddq;
};
using LaneJoints = std::array<LaneJoint, kNumJoints>;

// ^{i-1}R_i v and ^{i-1}R_i^T v as two plane rotations (JointGeometry::rotate, rotate_back).
LaneVector rotate(const JointGeometry& joint, const LaneJoint& angle, const LaneVector& v) {
  const Lane x = angle.cos_theta * v.x - angle.sin_theta * v.y;
  const Lane y = angle.sin_theta * v.x + angle.cos_theta * v.y;
  return {x, joint.cos_alpha * y - joint.sin_alpha * v.z, joint.sin_alpha * y + joint.cos_alpha * v.z};
}
LaneVector rotate_back(const JointGeometry& joint, const LaneJoint& angle, const LaneVector& v) {
  const Lane y = joint.cos_alpha * v.y + joint.sin_alpha * v.z;
  const Lane z = -joint.sin_alpha * v.y + joint.cos_alpha * v.z;
  return {angle.cos_theta * v.x + angle.sin_theta * y, -angle.sin_theta * v.x + angle.cos_theta * y, z};
}

// Angular velocity and acceleration of a link, and the linear acceleration of its origin (gravity
// included), in the link's frame.
struct LinkMotion {
  LaneVector w, dw, dv;
};

// The base accelerating upwards stands in for gravity (Craig sec. 6.5).
LinkMotion base_motion(const Model& model) { return {LaneVector{}, LaneVector{}, -broadcast(model.gravity())}; }

// Link i's motion from its parent's (Craig eqs. 6.45-6.47); the joint axis is the link's z.
LinkMotion outward(const JointGeometry& joint, const LaneJoint& angle, const LinkMotion& parent) {
  const LaneVector p = broadcast(joint.origin);
  const LaneVector dv_parent_at_origin = cross(parent.dw, p) + cross(parent.w, cross(parent.w, p)) + parent.dv;
  const LaneVector w_parent = rotate_back(joint, angle, parent.w);
  LinkMotion link;
  link.w = w_parent;
  link.w.z += angle.dq;                                   // w = w_parent + dq z
  link.dw = rotate_back(joint, angle, parent.dw);         // dw = R^T dw_parent + w_parent x dq z + ddq z
  link.dw.x += w_parent.y * angle.dq;
  link.dw.y -= w_parent.x * angle.dq;
  link.dw.z += angle.ddq;
  link.dv = rotate_back(joint, angle, dv_parent_at_origin);
  return link;
}

// A force and a moment about a frame origin.
struct LaneWrench {
  LaneVector force, moment;
};

// A wrench of link i (frame i) in frame i-1 about its origin: R f, R n + p x R f (Craig eqs. 6.51-6.52).
LaneWrench to_parent(const JointGeometry& child, const LaneJoint& angle, const LaneWrench& wrench) {
  const LaneVector force = rotate(child, angle, wrench.force);
  return {force, rotate(child, angle, wrench.moment) + cross(broadcast(child.origin), force)};
}

// Net wrench of a link about its origin (Craig eqs. 6.48-6.50 with h = m c, I_O = I_C - m [c]x^2).
LaneWrench net_wrench(const SpatialInertia& body, const LinkMotion& m) {
  const LaneVector h = broadcast(body.first_moment);
  return {Lane::Constant(body.mass) * m.dv + cross(m.dw, h) + cross(m.w, cross(m.w, h)),
          times(body.rotational, m.dw) + cross(m.w, times(body.rotational, m.w)) + cross(h, m.dv)};
}

// Column k of [a]x, a x e_k.
LaneVector skew_column(const LaneVector& a, int k) {
  const Lane zero = Lane::Zero();
  if (k == 0) return {zero, a.z, -a.y};
  if (k == 1) return {-a.z, zero, a.x};
  return {a.y, -a.x, zero};
}

// Column k of L(a), where I a = L(a) (Ixx, Ixy, Ixz, Iyy, Iyz, Izz) for a symmetric I.
LaneVector inertia_product_column(const LaneVector& a, int k) {
  const Lane zero = Lane::Zero();
  switch (k) {
    case 0: return {a.x, zero, zero};
    case 1: return {a.y, a.x, zero};
    case 2: return {a.z, zero, a.x};
    case 3: return {zero, a.y, zero};
    case 4: return {zero, a.z, a.y};
    default: return {zero, zero, a.z};
  }
}

// The net wrench of a link, linear in its standard parameters (m, h, I_O), column by column
// (regressor.cpp's link_regressor):  f = m dv + ([dw]x + [w]x [w]x) h,  n = -[dv]x h + L(dw) I + [w]x L(w) I.
using LaneRegressor = std::array<LaneWrench, kLinkParameters>;
LaneRegressor link_regressor(const LinkMotion& m) {
  LaneRegressor A;
  A[0] = {m.dv, LaneVector{}};
  for (int k = 0; k < 3; ++k)
    A[1 + k] = {skew_column(m.dw, k) + cross(m.w, skew_column(m.w, k)), -skew_column(m.dv, k)};
  for (int k = 0; k < 6; ++k)
    A[4 + k] = {LaneVector{}, inertia_product_column(m.dw, k) + cross(m.w, inertia_product_column(m.w, k))};
  return A;
}

// The batch in blocks of four states, with every joint angle's sine and cosine computed up front in
// one vectorised pass. The last block's unused lanes hold a state at rest (their results are dropped).
class Blocks {
 public:
  Blocks(const Model& model, const StateBatch& states, const char* caller) : states_(states) {
    if (states.dq.cols() != states.size() || states.ddq.cols() != states.size())
      throw std::invalid_argument(std::string(caller) + ": q, dq and ddq must hold the same number of states (" +
                                  std::to_string(states.size()) + ", " + std::to_string(states.dq.cols()) + ", " +
                                  std::to_string(states.ddq.cols()) + " columns)");
    count_ = (states.size() + kLanes - 1) / kLanes;
    const std::size_t angles = static_cast<std::size_t>(count_) * kNumJoints * kLanes;
    std::vector<double> theta(angles, 0.0);
    sin_.resize(angles);
    cos_.resize(angles);
    for (Eigen::Index k = 0; k < states.size(); ++k)
      for (int i = 0; i < kNumJoints; ++i)
        theta[index(k / kLanes, i) + k % kLanes] = states.q(i, k) + model.joint(i).theta_offset;
    detail::sin_cos_in_fours(theta.data(), sin_.data(), cos_.data(), static_cast<std::ptrdiff_t>(angles));
  }

  Eigen::Index count() const { return count_; }
  Eigen::Index first(Eigen::Index block) const { return kLanes * block; }
  int used(Eigen::Index block) const { return static_cast<int>(std::min<Eigen::Index>(kLanes, states_.size() - first(block))); }

  LaneJoints joints(Eigen::Index block) const {
    LaneJoints joints;
    for (int i = 0; i < kNumJoints; ++i) {
      LaneJoint& joint = joints[i];
      joint.cos_theta = Eigen::Map<const Lane>(&cos_[index(block, i)]);
      joint.sin_theta = Eigen::Map<const Lane>(&sin_[index(block, i)]);
      joint.dq = joint.ddq = Lane::Zero();
      for (int l = 0; l < used(block); ++l) {
        joint.dq[l] = states_.dq(i, first(block) + l);
        joint.ddq[l] = states_.ddq(i, first(block) + l);
      }
    }
    return joints;
  }

 private:
  static std::size_t index(Eigen::Index block, int joint) {
    return (static_cast<std::size_t>(block) * kNumJoints + static_cast<std::size_t>(joint)) * kLanes;
  }

  const StateBatch& states_;
  Eigen::Index count_ = 0;
  std::vector<double> sin_, cos_;   // [block][joint][lane]
};

}  // namespace

void rnea_batch(const Model& model, const StateBatch& states, JointMatrix& tau) {
  const Blocks blocks(model, states, "rnea_batch");
  tau.resize(kNumJoints, states.size());
  for (Eigen::Index b = 0; b < blocks.count(); ++b) {
    const LaneJoints joints = blocks.joints(b);
    std::array<LaneWrench, kNumJoints> net;
    LinkMotion motion = base_motion(model);
    for (int i = 0; i < kNumJoints; ++i) {
      motion = outward(model.joint(i), joints[i], motion);
      net[i] = net_wrench(model.body(i), motion);
    }
    // Inward: each link passes its wrench to its parent; tau_i is the z moment, plus the rotor's
    // I_a,i ddq_i (Featherstone sec. 7.3).
    LaneWrench carried;
    for (int i = kNumJoints - 1; i >= 0; --i) {
      if (i + 1 < kNumJoints) carried = to_parent(model.joint(i + 1), joints[i + 1], carried);
      carried = {carried.force + net[i].force, carried.moment + net[i].moment};
      const Lane tau_i = carried.moment.z + model.armature()[i] * joints[i].ddq;
      for (int l = 0; l < blocks.used(b); ++l) tau(i, blocks.first(b) + l) = tau_i[l];
    }
  }
}

// As InertialRegressor: Y(j, link i) = e_z . (^jX*_i A_i) for j <= i, zero above.
void inertial_regressor_batch(const Model& model, const StateBatch& states, Eigen::MatrixXd& Y) {
  const Blocks blocks(model, states, "inertial_regressor_batch");
  Y.setZero(kNumJoints * states.size(), kInertialParameters);
  for (Eigen::Index b = 0; b < blocks.count(); ++b) {
    const LaneJoints joints = blocks.joints(b);
    LinkMotion motion = base_motion(model);
    for (int i = 0; i < kNumJoints; ++i) {
      motion = outward(model.joint(i), joints[i], motion);
      LaneRegressor A = link_regressor(motion);
      for (int j = i;; --j) {
        for (int k = 0; k < kLinkParameters; ++k)
          for (int l = 0; l < blocks.used(b); ++l)
            Y(kNumJoints * (blocks.first(b) + l) + j, kLinkParameters * i + k) = A[k].moment.z[l];
        if (j == 0) break;
        for (LaneWrench& column : A) column = to_parent(model.joint(j), joints[j], column);
      }
    }
  }
}

}  // namespace csp
