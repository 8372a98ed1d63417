// Model: the immutable parameters of one 7-joint revolute arm described by Craig's modified
// Denavit-Hartenberg convention (kinematics, inertia, end effector and load, gravity, friction,
// limits). Data: the preallocated workspace the algorithms write into. Algorithms are free
// functions taking (const Model&, Data&, ...) and allocate nothing.
#pragma once

#include <array>

#include <Eigen/Cholesky>

#include "csp/dynamics/friction.hpp"
#include "csp/dynamics/limits.hpp"
#include "csp/dynamics/spatial.hpp"

namespace csp {

// One row of the modified-DH table: ^{i-1}T_i = RotX(alpha) TransX(a) RotZ(q_i + theta_offset) TransZ(d).
struct MdhParameters {
  double a = 0.0;
  double d = 0.0;
  double alpha = 0.0;
  double theta_offset = 0.0;
};

// ^{i-1}T_i of one MDH row at joint angle q (Craig eq. 3.6).
Transform mdh_transform(const MdhParameters& row, double q);

// One MDH row with its constant part evaluated once: ^{i-1}T_i = [RotX(alpha) | origin] RotZ(theta).
// The rotation RotX(alpha) RotZ(theta) is applied as two plane rotations (8 multiplications for a
// vector, about 30 for a symmetric matrix) instead of a full 3x3 product: the recursions spend most
// of their time there.
struct JointGeometry {
  double cos_alpha = 1.0;
  double sin_alpha = 0.0;
  double theta_offset = 0.0;
  Vector3 origin = Vector3::Zero();   // origin of frame i in frame i-1: (a, -sin(alpha) d, cos(alpha) d)

  Transform transform(double cos_theta, double sin_theta) const {
    Transform t;
    t.rotation << cos_theta, -sin_theta, 0.0,                                //
        cos_alpha * sin_theta, cos_alpha * cos_theta, -sin_alpha,           //
        sin_alpha * sin_theta, sin_alpha * cos_theta, cos_alpha;
    t.translation = origin;
    return t;
  }

  // ^{i-1}R_i v: a vector of frame i in frame i-1 (RotZ(theta), then RotX(alpha)).
  Vector3 rotate(double cos_theta, double sin_theta, const Vector3& v) const {
    const double x = cos_theta * v.x() - sin_theta * v.y();
    const double y = sin_theta * v.x() + cos_theta * v.y();
    return {x, cos_alpha * y - sin_alpha * v.z(), sin_alpha * y + cos_alpha * v.z()};
  }

  // ^{i-1}R_i^T v: a vector of frame i-1 in frame i.
  Vector3 rotate_back(double cos_theta, double sin_theta, const Vector3& v) const {
    const double y = cos_alpha * v.y() + sin_alpha * v.z();
    const double z = -sin_alpha * v.y() + cos_alpha * v.z();
    return {cos_theta * v.x() + sin_theta * y, -sin_theta * v.x() + cos_theta * y, z};
  }

  // R I R^T for a symmetric I given in frame i, expressed in frame i-1.
  Matrix3 rotate_symmetric(double cos_theta, double sin_theta, const Matrix3& I) const {
    Matrix3 out = I;
    rotate_in_plane(out, 0, 1, cos_theta, sin_theta);   // RotZ(theta): axes x, y
    rotate_in_plane(out, 1, 2, cos_alpha, sin_alpha);   // RotX(alpha): axes y, z
    return out;
  }

 private:
  // I <- G I G^T, G the rotation by (c, s) in the plane of axes i, j (new_i = c i - s j, new_j = s i + c j).
  static void rotate_in_plane(Matrix3& I, int i, int j, double c, double s) {
    const int k = 3 - i - j;
    const double ii = I(i, i), jj = I(j, j), ij = I(i, j), ik = I(i, k), jk = I(j, k);
    I(i, i) = c * c * ii - 2.0 * c * s * ij + s * s * jj;
    I(j, j) = s * s * ii + 2.0 * c * s * ij + c * c * jj;
    I(i, j) = I(j, i) = c * s * (ii - jj) + (c * c - s * s) * ij;
    I(i, k) = I(k, i) = c * ik - s * jk;
    I(j, k) = I(k, j) = s * ik + c * jk;
  }
};

// Everything that defines a Model, as plain values.
struct ModelParameters {
  std::array<MdhParameters, kNumJoints> joints{};
  Transform link7_T_flange;                           // ^7T_F (fixed MDH row)
  Transform F_T_EE;                                   // flange -> end effector (libfranka F_T_EE)
  Transform EE_T_K;                                   // end effector -> stiffness frame (EE_T_K)
  std::array<RigidBodyInertia, kNumJoints> links{};   // link i in MDH frame i
  RigidBodyInertia end_effector;                      // m_ee, F_x_Cee, I_ee (flange frame)
  RigidBodyInertia load;                              // m_load, F_x_Cload, I_load (flange frame)
  Vector3 gravity{0.0, 0.0, -9.81};                   // base frame [m/s^2] (libfranka gravity_earth)
  Vector7 armature = Vector7::Zero();                 // rotor inertia reflected to the link, I_a,i [kg m^2]
                                                      // (Pinocchio model.armature; Featherstone sec. 7.3)
  FrictionModel friction;
  JointLimits joint_limits;
  CartesianLimits cartesian_limits;
  bool physically_consistent = true;                  // false for fits such as libfranka_fit
};

class Model {
 public:
  explicit Model(const ModelParameters& parameters);

  const ModelParameters& parameters() const { return parameters_; }
  const JointGeometry& joint(int i) const { return joints_[i]; }
  const Vector3& gravity() const { return parameters_.gravity; }
  const Vector7& armature() const { return parameters_.armature; }

  // Spatial inertia of body i in its link frame, with end effector and load lumped on link 7
  // (what libfranka's set_load does to the dynamics).
  const SpatialInertia& body(int i) const { return bodies_[i]; }

  // The end effector and load combined, in the flange frame (libfranka m_total, F_x_Ctotal, I_total).
  const RigidBodyInertia& total_flange_load() const { return total_flange_load_; }

 private:
  ModelParameters parameters_;
  std::array<JointGeometry, kNumJoints> joints_{};
  std::array<SpatialInertia, kNumJoints> bodies_{};
  RigidBodyInertia total_flange_load_;
};

// Combine two rigid bodies given in one frame into one (mass-weighted CoM, parallel-axis theorem).
RigidBodyInertia combine(const RigidBodyInertia& a, const RigidBodyInertia& b);

// Model copies with one parameter changed, like libfranka's setLoad / setEE / setK.
Model with_load(const Model& model, const RigidBodyInertia& load);
Model with_gravity(const Model& model, const Vector3& gravity);

// Frames a pose or Jacobian can be asked for (libfranka franka::Frame).
enum class Frame { kJoint1, kJoint2, kJoint3, kJoint4, kJoint5, kJoint6, kJoint7, kFlange, kEndEffector, kStiffness };

struct Data {
  // Joint angles theta_i = q_i + theta_offset_i (every algorithm)
  Vector7 cos_theta = Vector7::Ones(), sin_theta = Vector7::Zero();

  // Kinematics (forward_kinematics)
  std::array<Transform, kNumJoints> O_T_joint{};        // ^0T_i
  Transform O_T_F, O_T_EE, O_T_K;
  std::array<Vector6, kNumJoints> axis{};               // joint motion subspace S_i at the base origin

  // Dynamics workspaces, base-frame spatial quantities
  std::array<SpatialInertia, kNumJoints> O_inertia{};   // body i, base frame (aba, coriolis_matrix)
  std::array<Vector6, kNumJoints> velocity{};           // v_i
  std::array<Vector6, kNumJoints> bias_acceleration{};  // c_i = v_i x S_i dq_i
  std::array<Vector6, kNumJoints> U{};                  // U_i, D_i, u_i (ABA)
  std::array<double, kNumJoints> D{};
  std::array<double, kNumJoints> u{};

  // Outputs
  Matrix7 mass_matrix = Matrix7::Zero();
  Matrix7 coriolis_matrix = Matrix7::Zero();
  Vector7 ddq = Vector7::Zero();
};

// External wrenches on the links: (force; moment) applied BY the environment ON link i,
// expressed in link frame i about its origin (linear first). Zero for no contact.
using LinkWrenches = std::array<Vector6, kNumJoints>;
extern const LinkWrenches kNoLinkWrenches;

// Positive definite and triangle inequality of the principal moments (a physical rigid body).
bool is_physical_inertia(const Matrix3& inertia_about_com);

}  // namespace csp
