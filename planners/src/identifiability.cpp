#include "csp/planners/identifiability.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/batch.hpp"

namespace csp::planners {

Vector7 real_log_torque_noise() { return (Vector7() << 0.28, 0.40, 0.25, 0.38, 0.09, 0.11, 0.03).finished(); }

namespace {

// The reference states that fix the column scaling S (see the header).
std::vector<JointSample> reference_states(const JointLimits& limits) {
  std::mt19937_64 engine(20261125);
  std::uniform_real_distribution<double> unit(0.0, 1.0), symmetric(-1.0, 1.0);
  std::vector<JointSample> states(1000);
  for (auto& s : states)
    for (int j = 0; j < kNumJoints; ++j) {
      s.q[j] = limits.q_min[j] + unit(engine) * (limits.q_max[j] - limits.q_min[j]);
      s.dq[j] = 0.6 * limits.dq_max[j] * symmetric(engine);
      s.ddq[j] = 0.5 * limits.ddq_max[j] * symmetric(engine);
    }
  return states;
}

}  // namespace

Eigen::VectorXd IdentificationModel::standard_parameters(const Model& model) {
  Eigen::VectorXd pi(kInertialParameters);
  for (int i = 0; i < kNumJoints; ++i) pi.segment<kLinkParameters>(kLinkParameters * i) = link_parameters(model.body(i));
  return pi;
}

IdentificationModel::IdentificationModel(const Model& model, const Vector7& noise_sigma)
    : model_(model), regressor_(model), standard_(standard_parameters(model)), sigma_(noise_sigma) {
  if (!(sigma_.array() > 0.0).all() || !sigma_.allFinite())
    throw std::invalid_argument("identification: the torque noise sigma must be positive on every joint");
  const BaseParameters base = csp::base_parameters(model);
  base_ = base.columns;
  std::vector<bool> is_base(kInertialParameters, false);
  for (int c : base_) is_base[c] = true;
  for (int c = 0; c < kInertialParameters; ++c)
    if (!is_base[c]) dependent_.push_back(c);
  const Eigen::MatrixXd Y_B = base.random_regressor(Eigen::all, base_);
  const Eigen::MatrixXd Y_D = base.random_regressor(Eigen::all, dependent_);
  beta_ = Y_B.householderQr().solve(Y_D);   // Y_D = Y_B beta (exact: the dependent columns are combinations)

  scale_ = Eigen::VectorXd::Ones(parameters());
  const Eigen::MatrixXd reference = stacked_scaled(reference_states(model.parameters().joint_limits));
  for (int c = 0; c < parameters(); ++c) {
    const double rms = reference.col(c).norm() / std::sqrt(static_cast<double>(reference.rows()));
    scale_[c] = rms > 0.0 ? 1.0 / rms : 1.0;
  }
}

std::vector<std::string> IdentificationModel::parameter_names() const {
  static const char* const kLink[kLinkParameters] = {"m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  static const char* const kFriction[kFrictionParametersPerJoint] = {"viscous", "coulomb", "offset"};
  std::vector<std::string> names;
  for (int c : base_) names.push_back("link" + std::to_string(c / kLinkParameters + 1) + "." + kLink[c % kLinkParameters]);
  for (int j = 0; j < kNumJoints; ++j)
    for (const char* f : kFriction) names.push_back("joint" + std::to_string(j + 1) + "." + f);
  return names;
}

namespace {

constexpr int kFrictionColumns = kFrictionParametersPerJoint * kNumJoints;
using FrictionRows = Eigen::Matrix<double, kNumJoints, kFrictionColumns>;

// One state's friction columns: [dq_j, tanh(dq_j / v), 1] on joint j's row, zero elsewhere.
FrictionRows friction_rows(const Vector7& dq) {
  FrictionRows F = FrictionRows::Zero();
  for (int j = 0; j < kNumJoints; ++j) {
    const int c = kFrictionParametersPerJoint * j;
    F(j, c) = dq[j];
    F(j, c + 1) = std::tanh(dq[j] / kCoulombVelocity);
    F(j, c + 2) = 1.0;
  }
  return F;
}

}  // namespace

Eigen::MatrixXd IdentificationModel::rows(Data& data, const JointSample& s, Vector7& model_torque) const {
  const InertialRegressorRows Y = regressor_(data, s.q, s.dq, s.ddq);
  model_torque = Y * standard_ + model_.armature().cwiseProduct(s.ddq) + friction_torque(model_.parameters().friction, s.dq);
  Eigen::MatrixXd R(kNumJoints, parameters());
  R.leftCols(base_parameters()) = Y(Eigen::all, base_);
  R.rightCols<kFrictionColumns>() = friction_rows(s.dq);
  return R;
}

Eigen::MatrixXd IdentificationModel::rows(Data& data, const JointSample& s) const {
  Vector7 unused;
  return rows(data, s, unused);
}

Eigen::MatrixXd IdentificationModel::scale_rows(const Eigen::MatrixXd& rows) const {
  return sigma_.cwiseInverse().asDiagonal() * rows * scale_.asDiagonal();
}

StateBatch state_batch(const std::vector<JointSample>& samples) {
  StateBatch states(static_cast<Eigen::Index>(samples.size()));
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto column = static_cast<Eigen::Index>(k);
    states.q.col(column) = samples[k].q;
    states.dq.col(column) = samples[k].dq;
    states.ddq.col(column) = samples[k].ddq;
  }
  return states;
}

// The inertial regressors of all samples at once (dynamics/batch.hpp), then each sample's friction columns.
Eigen::MatrixXd IdentificationModel::stacked(const std::vector<JointSample>& samples) const {
  Eigen::MatrixXd Y;
  inertial_regressor_batch(model_, state_batch(samples), Y);
  Eigen::MatrixXd W(Y.rows(), parameters());
  W.leftCols(base_parameters()) = Y(Eigen::all, base_);
  for (std::size_t k = 0; k < samples.size(); ++k)
    W.block<kNumJoints, kFrictionColumns>(kNumJoints * static_cast<Eigen::Index>(k), base_parameters()) =
        friction_rows(samples[k].dq);
  return W;
}

Eigen::MatrixXd IdentificationModel::stacked_scaled(const std::vector<JointSample>& samples) const {
  Eigen::MatrixXd W = stacked(samples);
  for (Eigen::Index r = 0; r < W.rows(); ++r) W.row(r) /= sigma_[r % kNumJoints];
  return W * scale_.asDiagonal();
}

Eigen::VectorXd IdentificationModel::parameters_of(const Model& plant) const {
  const Eigen::VectorXd pi = standard_parameters(plant);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(parameters());
  theta.head(base_parameters()) = pi(base_) + beta_ * pi(dependent_);
  const FrictionModel& friction = plant.parameters().friction;
  if (friction.type == FrictionModel::Type::kLinear)
    for (int j = 0; j < kNumJoints; ++j)
      theta.segment<kFrictionParametersPerJoint>(base_parameters() + kFrictionParametersPerJoint * j)
          << friction.viscous[j], friction.coulomb[j], friction.offset[j];
  return theta;
}

namespace {

struct Decomposition {
  Eigen::VectorXd eigenvalues;   // ascending, of A
  Eigen::MatrixXd vectors;
  double eps = 0.0;
  Eigen::MatrixXd inverse;       // (A + eps I)^-1
};

Decomposition decompose(const Eigen::MatrixXd& A) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  if (eig.info() != Eigen::Success) throw std::runtime_error("identifiability: eigendecomposition failed");
  Decomposition d;
  d.eigenvalues = eig.eigenvalues().cwiseMax(0.0);   // A is positive semidefinite; clip rounding
  d.vectors = eig.eigenvectors();
  d.eps = 1e-9 * A.trace() / static_cast<double>(A.rows());
  if (!(d.eps > 0.0)) d.eps = 1e-300;   // a motionless trajectory: every direction unidentified
  d.inverse = d.vectors * (d.eigenvalues.array() + d.eps).inverse().matrix().asDiagonal() * d.vectors.transpose();
  return d;
}

}  // namespace

Identifiability identifiability(const IdentificationModel& id, const Eigen::MatrixXd& scaled,
                                const Eigen::MatrixXd& task_scaled, double weight) {
  if (scaled.cols() != id.parameters())
    throw std::invalid_argument("identifiability: regressor with the wrong number of columns");
  return identifiability_of_information(id, weight * scaled.transpose() * scaled, task_scaled);
}

Identifiability identifiability_of_information(const IdentificationModel& id, const Eigen::MatrixXd& information,
                                               const Eigen::MatrixXd& task_scaled) {
  const int p = id.parameters();
  if (information.rows() != p || information.cols() != p || (task_scaled.rows() > 0 && task_scaled.cols() != p))
    throw std::invalid_argument("identifiability: information or task regressor of the wrong size");
  const Decomposition d = decompose(information);
  Identifiability out;
  out.parameters = p;
  out.singular_values = d.eigenvalues.reverse().cwiseSqrt();
  const double sigma_max = out.singular_values[0];
  out.rank = static_cast<int>((out.singular_values.array() > 1e-6 * sigma_max).count());
  out.sigma_min = out.singular_values[p - 1];
  out.condition_number = out.rank > 0 ? sigma_max / out.singular_values[out.rank - 1] : INFINITY;
  out.log_det = (d.eigenvalues.array() + d.eps).log().sum() / p;
  out.parameter_sigma = id.column_scale().cwiseProduct(d.inverse.diagonal().cwiseSqrt());
  if (task_scaled.rows() > 0) {
    out.task_criterion = (d.inverse * (task_scaled.transpose() * task_scaled)).trace() / static_cast<double>(task_scaled.rows());
    const Eigen::MatrixXd unidentified = d.vectors.leftCols(p - out.rank);   // ascending eigenvalues
    out.task_residual = (task_scaled * unidentified).norm() / task_scaled.norm();
    const Eigen::VectorXd variance = (task_scaled * d.inverse).cwiseProduct(task_scaled).rowwise().sum();
    Vector7 sum = Vector7::Zero();
    for (Eigen::Index r = 0; r < variance.size(); ++r) sum[r % kNumJoints] += variance[r];
    const double samples = static_cast<double>(task_scaled.rows() / kNumJoints);
    out.task_torque_sigma = (sum / samples).cwiseSqrt().cwiseProduct(id.noise_sigma());
  } else {
    out.task_criterion = out.task_residual = NAN;
  }
  return out;
}

Criterion design_criterion(const Eigen::MatrixXd& A, const Eigen::MatrixXd& task_information, int task_rows,
                           double lambda) {
  const Eigen::Index p = A.rows();
  const Decomposition d = decompose(A);
  const double deps_dA = 1e-9 / static_cast<double>(p);   // d eps / dA = (1e-9 / p) I
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(p, p);
  Criterion c;
  c.log_det = (d.eigenvalues.array() + d.eps).log().sum() / static_cast<double>(p);
  c.value = -c.log_det;
  // d(-(1/p) log det(A + eps I)) = -(1/p) (A + eps I)^-1 : (dA + deps I)
  c.gradient = -(d.inverse + d.inverse.trace() * deps_dA * I) / static_cast<double>(p);
  if (lambda > 0.0 && task_rows > 0) {
    const Eigen::MatrixXd inverse_B = d.inverse * task_information;
    c.task_criterion = inverse_B.trace() / task_rows;
    const Eigen::MatrixXd dJ = -inverse_B * d.inverse / task_rows;   // dJ/dA, and dJ/deps = tr(dJ)
    c.value += lambda * std::log(c.task_criterion);
    c.gradient += lambda / c.task_criterion * (dJ + dJ.trace() * deps_dA * I);
  }
  c.gradient = 0.5 * (c.gradient + c.gradient.transpose()).eval();
  return c;
}

Criterion condition_criterion(const Eigen::MatrixXd& A, int order) {
  const Eigen::Index p = A.rows();
  const Decomposition d = decompose(A);
  const double r = order;
  // Scaled by the largest and the smallest eigenvalue, so that mu^r and mu^-r neither overflow nor vanish.
  const Eigen::ArrayXd mu = d.eigenvalues.array() + d.eps;   // ascending
  Eigen::ArrayXd up(p), down(p);
  for (Eigen::Index i = 0; i < p; ++i) up[i] = std::pow(mu[i] / mu[p - 1], r), down[i] = std::pow(mu[0] / mu[i], r);
  Criterion c;
  c.value = (std::log(mu[p - 1]) + std::log(up.sum()) / r - std::log(mu[0]) + std::log(down.sum()) / r) / 2.0;
  c.log_det = mu.log().sum() / static_cast<double>(p);
  // d/dmu_i: (1/2) (mu_i^(r-1) / sum mu^r - mu_i^(-r-1) / sum mu^-r); dmu_i/dA = v_i v_i^T + deps/dA.
  const Eigen::ArrayXd dmu = 0.5 * (up / (mu * up.sum()) - down / (mu * down.sum()));
  const double deps_dA = 1e-9 / static_cast<double>(p);
  c.gradient = d.vectors * dmu.matrix().asDiagonal() * d.vectors.transpose();
  c.gradient += dmu.sum() * deps_dA * Eigen::MatrixXd::Identity(p, p);
  return c;
}

}  // namespace csp::planners
