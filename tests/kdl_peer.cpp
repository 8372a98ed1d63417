// KDL side (see kdl_peer.hpp): Eigen with the distribution KDL's alignment, before any include.
#define EIGEN_MAX_ALIGN_BYTES 16
#define EIGEN_MALLOC_ALREADY_ALIGNED 1
#define CSP_KDL_SIDE
#include "kdl_peer.hpp"

#include <stdexcept>
#include <string>

namespace csp::test {
namespace {

// RotX(alpha) TransX(a): the fixed part of an MDH row, ahead of its joint.
KDL::Frame mdh_fixed_part(const KdlDescription::MdhRow& row) { return KDL::Frame::DH_Craig1989(row.a, row.alpha, 0.0, 0.0); }

KDL::Chain build_dynamics_chain(const KdlDescription& description, std::array<KDL::Frame, kNumJoints>& tip_T_frame,
                                int& first_joint_segment) {
  const auto& rows = description.joints;
  KDL::Chain chain;
  // A fixed base segment carries row 1's RotX(alpha_1) TransX(a_1), unless that is the identity.
  first_joint_segment = rows[0].a == 0.0 && rows[0].alpha == 0.0 ? 0 : 1;
  if (first_joint_segment == 1)
    chain.addSegment(KDL::Segment("base", KDL::Joint("base_fixed", KDL::Joint::Fixed), mdh_fixed_part(rows[0])));

  for (int i = 0; i < kNumJoints; ++i) {
    const bool last = i + 1 == kNumJoints;
    // G_i: from MDH frame i to the segment tip (the next row's fixed part, or the flange).
    const KDL::Frame frame_T_tip = last ? to_kdl(description.link7_T_flange) : mdh_fixed_part(rows[i + 1]);
    tip_T_frame[i] = frame_T_tip.Inverse();

    // Link i's inertia is given in MDH frame i; KDL wants it in the segment tip frame.
    KDL::RigidBodyInertia inertia = tip_T_frame[i] * to_kdl(description.links[i]);
    // End effector and load sit in the flange frame, which is the tip of joint 7's segment.
    if (last) inertia = inertia + to_kdl(description.end_effector) + to_kdl(description.load);

    const std::string n = std::to_string(i + 1);
    const KDL::Joint joint("joint" + n, KDL::Joint::RotZ, 1.0, rows[i].theta_offset, description.armature[i]);
    chain.addSegment(KDL::Segment("link" + n, joint, KDL::Frame(KDL::Vector(0.0, 0.0, rows[i].d)) * frame_T_tip, inertia));
  }
  return chain;
}

// The kinematic chain goes on to the end effector. The EE segment is massless (end effector and
// load are lumped on link 7), so the dynamics solvers use the chain that stops at the flange.
KDL::Chain with_end_effector(const KDL::Chain& arm, const KdlDescription& description) {
  KDL::Chain chain = arm;
  chain.addSegment(KDL::Segment("end_effector", KDL::Joint("ee_fixed", KDL::Joint::Fixed), to_kdl(description.F_T_EE)));
  return chain;
}

void check(int error, const char* what) {
  if (error < 0) throw std::runtime_error(std::string("KDL ") + what + " failed with error " + std::to_string(error));
}

}  // namespace

KDL::Vector to_kdl(const Vector3& v) { return KDL::Vector(v.x(), v.y(), v.z()); }

KDL::Frame to_kdl(const Transform& transform) {
  const Matrix3& r = transform.rotation;
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
                    to_kdl(transform.translation));
}

KDL::JntArray to_kdl(const Vector7& values) {
  KDL::JntArray array(kNumJoints);
  array.data = values;
  return array;
}

KDL::RigidBodyInertia to_kdl(const RigidBodyInertia& body) {
  const Matrix3& i = body.inertia;
  return KDL::RigidBodyInertia(body.mass, to_kdl(body.com),
                               KDL::RotationalInertia(i(0, 0), i(1, 1), i(2, 2), i(0, 1), i(0, 2), i(1, 2)));
}

Transform to_csp(const KDL::Frame& frame) {
  Transform t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.rotation(r, c) = frame.M(r, c);
    t.translation[r] = frame.p(r);
  }
  return t;
}

KdlPeer::Kdl::Kdl(const KdlDescription& description)
    : dynamics_chain(build_dynamics_chain(description, tip_T_frame, first_joint_segment)),
      chain(with_end_effector(dynamics_chain, description)),
      fk(chain),
      jacobian(chain),
      id(dynamics_chain, to_kdl(description.gravity)),
      dyn(dynamics_chain, to_kdl(description.gravity)),
      fd(new KDL::ChainFdSolver_RNE(dynamics_chain, to_kdl(description.gravity))),
      no_wrenches(dynamics_chain.getNrOfSegments(), KDL::Wrench::Zero()),
      segment_poses(chain.getNrOfSegments()) {
  if (chain.getNrOfJoints() != kNumJoints) throw std::logic_error("KDL chain does not have 7 joints");
}

KdlPeer::KdlPeer(const KdlDescription& description) : kdl_(std::make_unique<Kdl>(description)) {}
KdlPeer::~KdlPeer() = default;
KdlPeer::KdlPeer(KdlPeer&&) noexcept = default;
KdlPeer& KdlPeer::operator=(KdlPeer&&) noexcept = default;

int KdlPeer::num_segments() const { return static_cast<int>(kdl_->chain.getNrOfSegments()); }
int KdlPeer::num_dynamics_segments() const { return static_cast<int>(kdl_->dynamics_chain.getNrOfSegments()); }

Vector7 KdlPeer::rnea(const Vector7& q, const Vector7& dq, const Vector7& ddq) {
  Kdl& k = *kdl_;
  k.q.data = q;
  k.dq.data = dq;
  k.ddq.data = ddq;
  check(k.id.CartToJnt(k.q, k.dq, k.ddq, k.no_wrenches, k.out), "ChainIdSolver_RNE::CartToJnt");
  return k.out.data;
}

Vector7 KdlPeer::gravity(const Vector7& q) {
  Kdl& k = *kdl_;
  k.q.data = q;
  check(k.dyn.JntToGravity(k.q, k.out), "ChainDynParam::JntToGravity");
  return k.out.data;
}

Vector7 KdlPeer::coriolis(const Vector7& q, const Vector7& dq) {
  Kdl& k = *kdl_;
  k.q.data = q;
  k.dq.data = dq;
  check(k.dyn.JntToCoriolis(k.q, k.dq, k.out), "ChainDynParam::JntToCoriolis");
  return k.out.data;
}

Matrix7 KdlPeer::mass(const Vector7& q) {
  Kdl& k = *kdl_;
  k.q.data = q;
  check(k.dyn.JntToMass(k.q, k.mass), "ChainDynParam::JntToMass");
  return k.mass.data;
}

Vector7 KdlPeer::forward_dynamics(const Vector7& q, const Vector7& dq, const Vector7& tau) {
  Kdl& k = *kdl_;
  k.q.data = q;
  k.dq.data = dq;
  k.ddq.data = tau;
  check(k.fd->CartToJnt(k.q, k.dq, k.ddq, k.no_wrenches, k.out), "ChainFdSolver_RNE::CartToJnt");
  return k.out.data;
}

Matrix6x7 KdlPeer::ee_jacobian(const Vector7& q) {
  Kdl& k = *kdl_;
  k.q.data = q;
  // Reference point: the chain tip (EE origin); reference frame: the base. Rows: (vel; rot).
  check(k.jacobian.JntToJac(k.q, k.jac), "ChainJntToJacSolver::JntToJac");
  return k.jac.data;
}

Transform KdlPeer::ee_pose(const Vector7& q) {
  Kdl& k = *kdl_;
  k.q.data = q;
  KDL::Frame pose;
  check(k.fk.JntToCart(k.q, pose), "ChainFkSolverPos_recursive::JntToCart");
  return to_csp(pose);
}

std::array<Transform, KdlPeer::kNumFrames> KdlPeer::frame_poses(const Vector7& q) {
  Kdl& k = *kdl_;
  k.q.data = q;
  check(k.fk.JntToCart(k.q, k.segment_poses), "ChainFkSolverPos_recursive::JntToCart (all segments)");
  std::array<Transform, kNumFrames> poses;
  for (int i = 0; i < kNumJoints; ++i) poses[i] = to_csp(k.segment_poses[k.first_joint_segment + i] * k.tip_T_frame[i]);
  poses[kNumJoints] = to_csp(k.segment_poses[k.first_joint_segment + kNumJoints - 1]);   // flange
  poses[kNumJoints + 1] = to_csp(k.segment_poses.back());                               // end effector
  return poses;
}

}  // namespace csp::test
