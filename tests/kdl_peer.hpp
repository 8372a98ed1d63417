// KDL (Orocos Kinematics and Dynamics Library) model of a csp::Model: the independent peer the
// tests cross-check against and the benchmarks compare with.
//
// Mapping of the modified-DH chain onto KDL segments. A KDL segment rotates about the z axis of
// its START frame and then applies its fixed f_tip; an MDH row applies its fixed part
// RotX(alpha_i) TransX(a_i) BEFORE the rotation RotZ(q_i + theta_i) TransZ(d_i). So the fixed part
// of row i+1 moves into segment i:
//
//   [base segment, fixed]  f_tip = RotX(alpha_1) TransX(a_1)              (only if not identity)
//   segment of joint i     RotZ(q_i + theta_i), f_tip = TransZ(d_i) G_i
//                            G_i = RotX(alpha_{i+1}) TransX(a_{i+1})      for i = 1..6
//                            G_7 = ^7T_F                                  (tip of joint 7 = flange)
//   EE segment, fixed      f_tip = F_T_EE                                 (kinematic chain only)
//
// The tip of joint i's segment is therefore MDH frame i times G_i, not frame i itself: link i's
// inertia (given in frame i) enters KDL as G_i^-1 * I_i, and frame i is recovered as tip_i G_i^-1.
// The end effector and load (given in the flange frame) are added to link 7 with KDL's own
// inertia arithmetic, independently of csp::combine / SpatialInertia::expressed_in. Only z-axis
// joints through the segment start are used (Joint::RotZ), not KDL's Joint with an origin.
//
// Eigen ABI. CSP is built with -march=native; on an AVX-512 machine Eigen then aligns heap
// memory to 64 bytes with its own malloc/free, while the distribution's liborocos-kdl was built
// for generic x86-64 (16 bytes, plain malloc). A KDL object (JntArray, Jacobian, the solvers'
// Eigen members) allocated inside libkdl and freed in a -march=native translation unit crashes.
// Therefore:
//   * every KDL object lives in KdlPeer::Kdl, which is defined only in "KDL side" translation
//     units: those that start with
//         #define EIGEN_MAX_ALIGN_BYTES 16          // dynamic-size data assumed 16-byte aligned
//         #define EIGEN_MALLOC_ALREADY_ALIGNED 1    // heap: plain malloc/free, as in libkdl
//         #define CSP_KDL_SIDE
//     before any include (kdl_peer.cpp, bench/bench_kdl.cpp). (EIGEN_MAX_ALIGN_BYTES alone
//     does not do: Eigen's heap alignment is the larger of it and the ISA's ideal alignment.);
//   * the rest of KdlPeer's interface uses only types whose layout does not depend on the
//     Eigen alignment (checked below), so CSP code built with any flags can call it.
#pragma once

#include <array>
#include <memory>

#include "csp/dynamics/spatial.hpp"
#ifndef CSP_KDL_SIDE
#include "csp/dynamics/model.hpp"
#endif

namespace csp::test {

// Shared by both sides: their layout must not depend on EIGEN_MAX_ALIGN_BYTES.
static_assert(alignof(Vector3) == alignof(double) && alignof(Matrix3) == alignof(double));
static_assert(alignof(Vector7) == alignof(double) && alignof(Matrix7) == alignof(double));
static_assert(alignof(Transform) == alignof(double) && alignof(RigidBodyInertia) == alignof(double));
static_assert(alignof(Matrix6x7) == 16, "6x7 doubles are 16-byte aligned with any Eigen alignment");

// What the KDL chain is built from: a csp::Model's parameters as alignment-independent values.
struct KdlDescription {
  struct MdhRow {
    double a, d, alpha, theta_offset;
  };
  std::array<MdhRow, kNumJoints> joints{};
  Transform link7_T_flange, F_T_EE;
  std::array<RigidBodyInertia, kNumJoints> links{};   // link i in MDH frame i
  RigidBodyInertia end_effector, load;                // flange frame
  Vector3 gravity = Vector3::Zero();
  std::array<double, kNumJoints> armature{};          // KDL::Joint inertia (rotor inertia on the joint axis)
};

class KdlPeer {
 public:
  // Joint frames 1..7, flange, end effector: the frames csp::Frame::kJoint1..kEndEffector name.
  static constexpr int kNumFrames = kNumJoints + 2;

#ifndef CSP_KDL_SIDE
  explicit KdlPeer(const Model& model) : KdlPeer(describe(model)) {}
  static KdlDescription describe(const Model& model);
#endif
  explicit KdlPeer(const KdlDescription& description);
  ~KdlPeer();
  KdlPeer(KdlPeer&&) noexcept;
  KdlPeer& operator=(KdlPeer&&) noexcept;

  // tau = M ddq + C dq + g (ChainIdSolver_RNE, no external wrenches).
  Vector7 rnea(const Vector7& q, const Vector7& dq, const Vector7& ddq);
  Vector7 gravity(const Vector7& q);                         // ChainDynParam::JntToGravity
  Vector7 coriolis(const Vector7& q, const Vector7& dq);     // C(q,dq) dq, ChainDynParam::JntToCoriolis
  Matrix7 mass(const Vector7& q);                            // ChainDynParam::JntToMass
  Vector7 forward_dynamics(const Vector7& q, const Vector7& dq, const Vector7& tau);   // ChainFdSolver_RNE
  // Base-frame geometric Jacobian of the EE origin, linear rows first (ChainJntToJacSolver).
  Matrix6x7 ee_jacobian(const Vector7& q);
  Transform ee_pose(const Vector7& q);                       // ^0T_EE
  std::array<Transform, kNumFrames> frame_poses(const Vector7& q);

  int num_segments() const;            // kinematic chain, base -> EE
  int num_dynamics_segments() const;   // dynamics chain, base -> flange

  // The KDL chains, solvers and workspaces; complete only on the KDL side (see above).
  struct Kdl;
  Kdl& kdl() { return *kdl_; }

 private:
  std::unique_ptr<Kdl> kdl_;   // on the heap: the KDL solvers keep references to the chains
};

#ifndef CSP_KDL_SIDE
inline KdlDescription KdlPeer::describe(const Model& model) {
  const ModelParameters& p = model.parameters();
  KdlDescription d;
  for (int i = 0; i < kNumJoints; ++i) {
    d.joints[i] = {p.joints[i].a, p.joints[i].d, p.joints[i].alpha, p.joints[i].theta_offset};
    d.links[i] = p.links[i];
  }
  d.link7_T_flange = p.link7_T_flange;
  d.F_T_EE = p.F_T_EE;
  d.end_effector = p.end_effector;
  d.load = p.load;
  d.gravity = model.gravity();
  Vector7::Map(d.armature.data()) = model.armature();
  return d;
}
#endif

}  // namespace csp::test

#ifdef CSP_KDL_SIDE
#if !defined(EIGEN_MAX_ALIGN_BYTES) || EIGEN_MAX_ALIGN_BYTES != 16 || !defined(EIGEN_MALLOC_ALREADY_ALIGNED) || \
    EIGEN_MALLOC_ALREADY_ALIGNED != 1
#error "KDL side translation units must define EIGEN_MAX_ALIGN_BYTES 16 and EIGEN_MALLOC_ALREADY_ALIGNED 1 before any include (see kdl_peer.hpp)"
#endif

#include <vector>

#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/jntspaceinertiamatrix.hpp>

namespace csp::test {

KDL::Vector to_kdl(const Vector3& v);
KDL::Frame to_kdl(const Transform& transform);
KDL::JntArray to_kdl(const Vector7& values);
// Mass, CoM and inertia about the CoM, all in one frame -> KDL inertia about that frame's origin.
KDL::RigidBodyInertia to_kdl(const RigidBodyInertia& body);
Transform to_csp(const KDL::Frame& frame);

struct KdlPeer::Kdl {
  explicit Kdl(const KdlDescription& description);
  Kdl(const Kdl&) = delete;
  Kdl& operator=(const Kdl&) = delete;

  std::array<KDL::Frame, kNumJoints> tip_T_frame{};   // G_i^-1: tip of joint i's segment -> MDH frame i
  int first_joint_segment = 0;                         // 1 if there is a fixed base segment
  // Declared before the solvers, which are built from (and keep references to) them.
  KDL::Chain dynamics_chain;   // base -> flange, link 7 carrying end effector and load
  KDL::Chain chain;            // base -> EE: dynamics_chain plus a massless fixed F_T_EE segment
  KDL::ChainFkSolverPos_recursive fk;
  KDL::ChainJntToJacSolver jacobian;
  KDL::ChainIdSolver_RNE id;
  KDL::ChainDynParam dyn;
  // A ChainFdSolver_RNE. Its destructor is inline in KDL's header and frees Eigen members; held
  // through the base class it is destroyed by libkdl's own (virtual) destructor, so unoptimised
  // builds, where the linker may pick another translation unit's copy of Eigen's inline free
  // functions, stay safe.
  std::unique_ptr<KDL::ChainFdSolver> fd;
  KDL::Wrenches no_wrenches;   // one zero wrench per dynamics segment

  // Workspaces
  KDL::JntArray q{kNumJoints}, dq{kNumJoints}, ddq{kNumJoints}, out{kNumJoints};
  KDL::JntSpaceInertiaMatrix mass{kNumJoints};
  KDL::Jacobian jac{kNumJoints};
  std::vector<KDL::Frame> segment_poses;
};

}  // namespace csp::test
#endif
