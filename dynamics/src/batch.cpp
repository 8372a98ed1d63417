// RNEA and the inertial regressor over many states (batch.hpp): the Newton-Euler recursion of
// rnea.cpp and regressor.cpp on four states at once, every scalar a lane of one AVX2 register. The
// equations are theirs: outward Craig eqs. 6.45-6.47, each link's wrench about its origin eqs.
// 6.48-6.50, inward eqs. 6.51-6.53; for the regressor each link's wrench as its 6x10 regressor in
// the standard parameters (Atkeson, An and Hollerbach 1986), carried inward column by column.
#include "csp/dynamics/batch.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>
#include <string>

#include "steps.hpp"

namespace csp {
namespace {

constexpr int kLanes = 4;   // doubles in one AVX2 register: four states per instruction
// The vector extension of GCC and Clang: arithmetic lane by lane, a scalar operand applies to every
// lane. (Eigen::Array4d computes the same, but GCC copies it through general registers between the
// inlined steps, and the half-width stores stall the full-width loads that follow.)
using Lane = double __attribute__((vector_size(kLanes * sizeof(double))));

Lane constant(double value) { return Lane{} + value; }
Lane load(const double* values) {
  Lane lane;
  std::memcpy(&lane, values, sizeof lane);
  return lane;
}

// The lane helpers are inlined into the recursion, so that its lanes stay in registers: called, each
// returns its vectors through memory, which cost more than the arithmetic.
#define CSP_LANE [[gnu::always_inline]] inline

// A 3-vector of each of four states.
struct LaneVector {
  Lane x{}, y{}, z{};
};

CSP_LANE LaneVector broadcast(const Vector3& v) { return {constant(v.x()), constant(v.y()), constant(v.z())}; }
CSP_LANE LaneVector operator+(const LaneVector& a, const LaneVector& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
CSP_LANE LaneVector operator-(const LaneVector& a) { return {-a.x, -a.y, -a.z}; }
CSP_LANE LaneVector operator*(const Lane& s, const LaneVector& v) { return {s * v.x, s * v.y, s * v.z}; }

CSP_LANE LaneVector cross(const LaneVector& a, const LaneVector& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// I v with the same matrix I for the four states.
CSP_LANE LaneVector times(const Matrix3& I, const LaneVector& v) {
  return {I(0, 0) * v.x + I(0, 1) * v.y + I(0, 2) * v.z,  //
          I(1, 0) * v.x + I(1, 1) * v.y + I(1, 2) * v.z,  //
          I(2, 0) * v.x + I(2, 1) * v.y + I(2, 2) * v.z};
}

// One joint of four states: cos and sin of theta = q + theta_offset, dq, ddq.
struct LaneJoint {
  Lane cos_theta, sin_theta, dq, ddq;
};

// ^{i-1}R_i v and ^{i-1}R_i^T v as two plane rotations (JointGeometry::rotate, rotate_back).
CSP_LANE LaneVector rotate(const JointGeometry& joint, const LaneJoint& angle, const LaneVector& v) {
  const Lane x = angle.cos_theta * v.x - angle.sin_theta * v.y;
  const Lane y = angle.sin_theta * v.x + angle.cos_theta * v.y;
  return {x, joint.cos_alpha * y - joint.sin_alpha * v.z, joint.sin_alpha * y + joint.cos_alpha * v.z};
}
CSP_LANE LaneVector rotate_back(const JointGeometry& joint, const LaneJoint& angle, const LaneVector& v) {
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
CSP_LANE LinkMotion base_motion(const Model& model) { return {LaneVector{}, LaneVector{}, -broadcast(model.gravity())}; }

// Link i's motion from its parent's (Craig eqs. 6.45-6.47); the joint axis is the link's z.
CSP_LANE LinkMotion outward(const JointGeometry& joint, const LaneJoint& angle, const LinkMotion& parent) {
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
CSP_LANE LaneWrench to_parent(const JointGeometry& child, const LaneJoint& angle, const LaneWrench& wrench) {
  const LaneVector force = rotate(child, angle, wrench.force);
  return {force, rotate(child, angle, wrench.moment) + cross(broadcast(child.origin), force)};
}

// Net wrench of a link about its origin (Craig eqs. 6.48-6.50 with h = m c, I_O = I_C - m [c]x^2).
CSP_LANE LaneWrench net_wrench(const SpatialInertia& body, const LinkMotion& m) {
  const LaneVector h = broadcast(body.first_moment);
  return {constant(body.mass) * m.dv + cross(m.dw, h) + cross(m.w, cross(m.w, h)),
          times(body.rotational, m.dw) + cross(m.w, times(body.rotational, m.w)) + cross(h, m.dv)};
}

// Column k of [a]x, a x e_k.
CSP_LANE LaneVector skew_column(const LaneVector& a, int k) {
  const Lane zero{};
  if (k == 0) return {zero, a.z, -a.y};
  if (k == 1) return {-a.z, zero, a.x};
  return {a.y, -a.x, zero};
}

// Column k of L(a), where I a = L(a) (Ixx, Ixy, Ixz, Iyy, Iyz, Izz) for a symmetric I.
CSP_LANE LaneVector inertia_product_column(const LaneVector& a, int k) {
  const Lane zero{};
  switch (k) {
    case 0: return {a.x, zero, zero};
    case 1: return {a.y, a.x, zero};
    case 2: return {a.z, zero, a.x};
    case 3: return {zero, a.y, zero};
    case 4: return {zero, a.z, a.y};
    default: return {zero, zero, a.z};
  }
}

// The net wrench of a link, linear in its standard parameters, column by column (regressor.cpp's
// link_regressor):  f = m dv + ([dw]x + [w]x [w]x) h,  n = -[dv]x h + L(dw) I + [w]x L(w) I.
// The six columns of I_O have no force, and a pure moment stays pure as it is carried inward
// (n' = R n): they are kept as moments alone, about a third of the work of moving a wrench.
struct LaneRegressor {
  std::array<LaneWrench, 4> mass_and_first_moment;   // m, hx, hy, hz
  std::array<LaneVector, 6> inertia;                 // Ixx, Ixy, Ixz, Iyy, Iyz, Izz: moments
};
CSP_LANE LaneRegressor link_regressor(const LinkMotion& m) {
  LaneRegressor A;
  A.mass_and_first_moment[0] = {m.dv, LaneVector{}};
  for (int k = 0; k < 3; ++k)
    A.mass_and_first_moment[1 + k] = {skew_column(m.dw, k) + cross(m.w, skew_column(m.w, k)), -skew_column(m.dv, k)};
  for (int k = 0; k < 6; ++k) A.inertia[k] = inertia_product_column(m.dw, k) + cross(m.w, inertia_product_column(m.w, k));
  return A;
}

// The regressor moved to frame i-1, as to_parent for each column.
CSP_LANE void to_parent(const JointGeometry& child, const LaneJoint& angle, LaneRegressor& A) {
  for (LaneWrench& column : A.mass_and_first_moment) column = to_parent(child, angle, column);
  for (LaneVector& moment : A.inertia) moment = rotate(child, angle, moment);
}

void check_state_counts(const StateBatch& states, const char* caller) {
  if (states.dq.cols() != states.size() || states.ddq.cols() != states.size())
    throw std::invalid_argument(std::string(caller) + ": q, dq and ddq must hold the same number of states (" +
                                std::to_string(states.size()) + ", " + std::to_string(states.dq.cols()) + ", " +
                                std::to_string(states.ddq.cols()) + " columns)");
}

Eigen::Index block_count(const StateBatch& states) { return (states.size() + kLanes - 1) / kLanes; }

// States 4 b .. 4 b + 3 of a batch as lanes, [joint][lane]: the sines and cosines of all 28 joint
// angles in one vectorised call, dq and ddq. In the last block the unused lanes hold a state at rest
// at theta = 0; their results are dropped.
class LaneBlock {
 public:
  LaneBlock(const Model& model, const StateBatch& states, Eigen::Index block)
      : first_(kLanes * block), used_(static_cast<int>(std::min<Eigen::Index>(kLanes, states.size() - first_))) {
    alignas(32) double theta[kNumJoints * kLanes] = {};
    for (int l = 0; l < used_; ++l)
      for (int i = 0; i < kNumJoints; ++i) {
        theta[kLanes * i + l] = states.q(i, first_ + l) + model.joint(i).theta_offset;
        dq_[kLanes * i + l] = states.dq(i, first_ + l);
        ddq_[kLanes * i + l] = states.ddq(i, first_ + l);
      }
    detail::sin_cos_in_fours(theta, sin_, cos_, kNumJoints * kLanes);
  }

  Eigen::Index first() const { return first_; }   // the batch's index of lane 0
  int used() const { return used_; }

  CSP_LANE LaneJoint joint(int i) const {
    return {load(&cos_[kLanes * i]), load(&sin_[kLanes * i]), load(&dq_[kLanes * i]), load(&ddq_[kLanes * i])};
  }

 private:
  Eigen::Index first_;
  int used_;
  alignas(32) double sin_[kNumJoints * kLanes], cos_[kNumJoints * kLanes];
  alignas(32) double dq_[kNumJoints * kLanes] = {}, ddq_[kNumJoints * kLanes] = {};
};

#undef CSP_LANE   // (a unity build puts other files after this one)

}  // namespace

void rnea_batch(const Model& model, const StateBatch& states, JointMatrix& tau) {
  check_state_counts(states, "rnea_batch");
  tau.resize(kNumJoints, states.size());
  for (Eigen::Index b = 0; b < block_count(states); ++b) {
    const LaneBlock block(model, states, b);
    std::array<LaneWrench, kNumJoints> net;
    LinkMotion motion = base_motion(model);
    for (int i = 0; i < kNumJoints; ++i) {
      motion = outward(model.joint(i), block.joint(i), motion);
      net[i] = net_wrench(model.body(i), motion);
    }
    // Inward: each link passes its wrench to its parent; tau_i is the z moment, plus the rotor's
    // I_a,i ddq_i (Featherstone sec. 7.3).
    LaneWrench carried;
    for (int i = kNumJoints - 1; i >= 0; --i) {
      if (i + 1 < kNumJoints) carried = to_parent(model.joint(i + 1), block.joint(i + 1), carried);
      carried = {carried.force + net[i].force, carried.moment + net[i].moment};
      const Lane tau_i = carried.moment.z + model.armature()[i] * block.joint(i).ddq;
      for (int l = 0; l < block.used(); ++l) tau(i, block.first() + l) = tau_i[l];
    }
  }
}

// As InertialRegressor: Y(j, link i) = e_z . (^jX*_i A_i) for j <= i, zero above. Each block of four
// states fills its 28 rows in a local copy first, so that Y is written in runs of 28 per column.
void inertial_regressor_batch(const Model& model, const StateBatch& states, Eigen::MatrixXd& Y) {
  check_state_counts(states, "inertial_regressor_batch");
  Y.resize(kNumJoints * states.size(), kInertialParameters);
  // Row 7 l + j: joint j of lane l. Every block writes the same entries (j <= i); the rest stay zero.
  Eigen::Matrix<double, kNumJoints * kLanes, kInertialParameters> block_rows =
      Eigen::Matrix<double, kNumJoints * kLanes, kInertialParameters>::Zero();
  for (Eigen::Index b = 0; b < block_count(states); ++b) {
    const LaneBlock block(model, states, b);
    const auto put = [&](int j, int column, const Lane& torque) {
      for (int l = 0; l < kLanes; ++l) block_rows(kNumJoints * l + j, column) = torque[l];
    };
    LinkMotion motion = base_motion(model);
    for (int i = 0; i < kNumJoints; ++i) {
      motion = outward(model.joint(i), block.joint(i), motion);
      LaneRegressor A = link_regressor(motion);
      for (int j = i;; --j) {
        for (int k = 0; k < 4; ++k) put(j, kLinkParameters * i + k, A.mass_and_first_moment[k].moment.z);
        for (int k = 0; k < 6; ++k) put(j, kLinkParameters * i + 4 + k, A.inertia[k].z);
        if (j == 0) break;
        to_parent(model.joint(j), block.joint(j), A);
      }
    }
    Y.middleRows(kNumJoints * block.first(), kNumJoints * block.used()) = block_rows.topRows(kNumJoints * block.used());
  }
}

}  // namespace csp
