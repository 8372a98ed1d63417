// How well a motion identifies the arm's dynamics (docs/excitation.md; planning-notes sections 1, 7).
//
// Parameters theta (p of them): the base inertial parameters (Gautier & Khalil 1990; 43 for the
// Panda, found by base_parameters in dynamics/regressor.hpp) and three friction numbers per joint,
// the columns [dq_j, tanh(dq_j / 0.01), 1] (Gaz et al.'s linear model: viscous, Coulomb, offset):
// p = 43 + 21 = 64. Per state, tau - armature ddq = R(q, dq, ddq) theta, R 7 x p.
//
// Stacked over K states, W (7K x p), scaled W^ = Sigma^-1/2 W S: Sigma = diag(sigma_j^2), the
// torque noise per joint; S = diag(s_c), s_c = 1 / RMS of column c of Sigma^-1/2 W over a fixed
// reference set (1000 seeded random states: q uniform inside the limits, dq within +-0.6 dq_max,
// ddq within +-0.5 ddq_max). Condition numbers depend on S: this is the S they are quoted with.
//
// With noise e ~ N(0, Sigma) on the torques, the weighted least-squares estimate has covariance
// S (W^T W^)^-1 S (in physical units); everything below comes from one eigendecomposition of
// A = W^T W^ (+ eps I, eps = 1e-9 tr(A)/p, which keeps unidentified directions finite but huge).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "csp/dynamics/batch.hpp"
#include "csp/dynamics/regressor.hpp"
#include "csp/planners/fourier.hpp"

namespace csp::planners {

// The noise floor of the real Panda log (../shared/data/real/, planning-notes section 1) [N m].
Vector7 real_log_torque_noise();

// Velocity of the Coulomb column's tanh [rad/s].
constexpr double kCoulombVelocity = 0.01;
constexpr int kFrictionParametersPerJoint = 3;

// The samples' (q, dq, ddq) as one batch for dynamics/batch.hpp (column k: sample k).
StateBatch state_batch(const std::vector<JointSample>& samples);

class IdentificationModel {
 public:
  // `model`: the arm with its tool (with_tool); noise_sigma > 0 per joint.
  explicit IdentificationModel(const Model& model, const Vector7& noise_sigma = real_log_torque_noise());

  int parameters() const { return static_cast<int>(base_.size()) + kFrictionParametersPerJoint * kNumJoints; }
  int base_parameters() const { return static_cast<int>(base_.size()); }
  const Vector7& noise_sigma() const { return sigma_; }
  const Eigen::VectorXd& column_scale() const { return scale_; }   // S
  const Model& model() const { return model_; }
  const std::vector<int>& base_columns() const { return base_; }   // standard-parameter index of each base column
  const Eigen::VectorXd& standard() const { return standard_; }     // the model's own 70
  // "link3.hz" for base columns (the standard parameter that carries the combination), "joint2.viscous" ...
  std::vector<std::string> parameter_names() const;

  // R(q, dq, ddq), physical units (7 x p).
  Eigen::MatrixXd rows(Data& data, const JointSample& s) const;
  // The torque the model needs, tau = R theta + armature ddq + (friction of the model), and R, at once.
  Eigen::MatrixXd rows(Data& data, const JointSample& s, Vector7& model_torque) const;
  // Stacked physical rows (7K x p) and the scaled W^ = Sigma^-1/2 W S.
  Eigen::MatrixXd stacked(const std::vector<JointSample>& samples) const;
  Eigen::MatrixXd stacked_scaled(const std::vector<JointSample>& samples) const;
  // Sigma^-1/2 R S for one state's physical rows.
  Eigen::MatrixXd scale_rows(const Eigen::MatrixXd& rows) const;

  // theta of an arm with the same kinematics (a plant): its base parameter values (the base
  // combinations of its 70 standard parameters, pi_B + beta pi_D with Y_D = Y_B beta) and, for a
  // linear friction model, its viscous, Coulomb and offset numbers (zero otherwise).
  Eigen::VectorXd parameters_of(const Model& plant) const;

  // Standard parameters of a model, its end effector and load lumped on link 7 (70).
  static Eigen::VectorXd standard_parameters(const Model& model);

 private:
  Model model_;
  InertialRegressor regressor_;
  std::vector<int> base_, dependent_;
  Eigen::MatrixXd beta_;          // base x dependent
  Eigen::VectorXd standard_;      // the model's own 70 parameters
  Vector7 sigma_;
  Eigen::VectorXd scale_;
};

// Criteria of a scaled stacked regressor (planning-notes section 1 table).
struct Identifiability {
  int parameters = 0;
  int rank = 0;                      // singular values > 1e-6 sigma_max
  double condition_number = 0.0;     // sigma_max / smallest identified singular value
  double log_det = 0.0;              // (1/p) log det(A + eps I), A = W^T W^ (D-criterion: its negative)
  double sigma_min = 0.0;            // smallest singular value of W^
  Eigen::VectorXd singular_values;   // of W^, descending
  Eigen::VectorXd parameter_sigma;   // predicted standard deviation per parameter, physical units
  // With task samples (NaN / zero without):
  double task_criterion = 0.0;       // J_t = tr((A + eps I)^-1 W^_t^T W^_t) / n_t: mean predicted torque variance / sigma^2
  double task_residual = 0.0;        // r_t = |W^_t (I - P_x)|_F / |W^_t|_F, P_x: projector on the identified row space
  Vector7 task_torque_sigma = Vector7::Zero();   // per joint, RMS over the task of the predicted torque sigma [N m]
};

// `scaled`: W^; `task_scaled`: W^_t (may have zero rows: no task); `weight`: A = weight W^T W^
// (e.g. the number of periods when W^ holds one period).
Identifiability identifiability(const IdentificationModel& id, const Eigen::MatrixXd& scaled,
                                const Eigen::MatrixXd& task_scaled, double weight = 1.0);
// The same from the information A = W^T W^ itself (e.g. summed over the segments of a plan).
Identifiability identifiability_of_information(const IdentificationModel& id, const Eigen::MatrixXd& information,
                                               const Eigen::MatrixXd& task_scaled);

// The design criterion Phi = -(1/p) log det(A + eps I) + lambda log J_t (lambda = 0 or no task: the
// D-criterion alone) and dPhi/dA (p x p, symmetric; eps = 1e-9 tr(A)/p is differentiated too).
struct Criterion {
  double value = 0.0;
  double log_det = 0.0;
  double task_criterion = 0.0;
  Eigen::MatrixXd gradient;   // dPhi/dA
};
Criterion design_criterion(const Eigen::MatrixXd& A, const Eigen::MatrixXd& task_information, int task_rows,
                           double lambda);

// The condition-number criterion: a smooth surrogate of log kappa(W^) = (1/2) log(lambda_max / lambda_min)
// of A + eps I, the Schatten-norm ratio (1/(2r)) [log sum mu_i^r + log sum mu_i^-r] (mu: the
// eigenvalues of A + eps I). It lies between log kappa and log kappa + (1/r) log p, and is smooth
// where log kappa is not (at an eigenvalue of multiplicity > 1, where minimising the ratio of the
// extreme eigenvalues drives them), which a gradient method such as MMA needs. Gradient dPhi/dA
// as in design_criterion; task_criterion is left 0.
inline constexpr int kConditionOrder = 8;   // r
Criterion condition_criterion(const Eigen::MatrixXd& A, int order = kConditionOrder);

}  // namespace csp::planners
