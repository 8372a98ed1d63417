#include "csp/planners/fourier.hpp"

#include "csp/dynamics/algorithms.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <Eigen/SVD>

namespace csp::planners {

FourierSeries::FourierSeries(double fundamental_hz, Coefficients a, Coefficients b, const Vector7& q0)
    : fundamental_hz_(fundamental_hz), omega_(2.0 * std::numbers::pi * fundamental_hz), a_(std::move(a)),
      b_(std::move(b)), q0_(q0) {
  if (!(fundamental_hz > 0.0) || !std::isfinite(fundamental_hz))
    throw std::invalid_argument("Fourier series: the fundamental frequency must be positive and finite");
  if (a_.cols() < 1 || a_.cols() != b_.cols())
    throw std::invalid_argument("Fourier series: a and b need the same number (>= 1) of harmonics");
}

Eigen::MatrixXd rest_to_rest_basis(int harmonics) {
  if (harmonics < 2) throw std::invalid_argument("rest-to-rest Fourier series need at least 2 harmonics");
  const int n = harmonics;
  Eigen::MatrixXd conditions = Eigen::MatrixXd::Zero(3, 2 * n);
  for (int l = 1; l <= n; ++l) {
    conditions(0, l - 1) = 1.0;                      // dq(0)   = sum a_l
    conditions(1, n + l - 1) = l;                    // ddq(0)  = w sum l b_l
    conditions(2, l - 1) = static_cast<double>(l * l);   // dddq(0) = -w^2 sum l^2 a_l
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(conditions, Eigen::ComputeFullV);
  return svd.matrixV().rightCols(2 * n - 3);   // rank 3: the last 2N-3 right singular vectors
}

FourierSeries FourierSeries::rest_to_rest(double fundamental_hz, int harmonics, const Eigen::MatrixXd& free,
                                          const Vector7& anchor) {
  const Eigen::MatrixXd basis = rest_to_rest_basis(harmonics);
  if (free.rows() != kNumJoints || free.cols() != basis.cols())
    throw std::invalid_argument("rest-to-rest Fourier series: expected 7 x " + std::to_string(basis.cols()) +
                                " free coefficients");
  const Eigen::MatrixXd ab = free * basis.transpose();   // 7 x 2N: [a | b]
  Coefficients a = ab.leftCols(harmonics), b = ab.rightCols(harmonics);
  const double omega = 2.0 * std::numbers::pi * fundamental_hz;
  Vector7 q0 = anchor;
  for (int l = 1; l <= harmonics; ++l) q0 += b.col(l - 1) / (omega * l);   // q(0) = q0 - sum b/(w l) = anchor
  return FourierSeries(fundamental_hz, std::move(a), std::move(b), q0);
}

JointSample FourierSeries::sample(double t) const {
  JointSample s;
  s.q = q0_;
  for (int l = 1; l <= harmonics(); ++l) {
    const double w = omega_ * l;
    const double c = std::cos(w * t), sn = std::sin(w * t);
    const auto a = a_.col(l - 1), b = b_.col(l - 1);
    s.q += (a * sn - b * c) / w;
    s.dq += a * c + b * sn;
    s.ddq += w * (b * c - a * sn);
    s.dddq -= w * w * (a * c + b * sn);
  }
  return s;
}

FourierBounds FourierSeries::bounds() const {
  FourierBounds bounds{Vector7::Zero(), Vector7::Zero(), Vector7::Zero(), Vector7::Zero()};
  for (int l = 1; l <= harmonics(); ++l) {
    const double w = omega_ * l;
    const Vector7 rho = (a_.col(l - 1).array().square() + b_.col(l - 1).array().square()).sqrt();
    bounds.q_deviation += rho / w;
    bounds.dq += rho;
    bounds.ddq += w * rho;
    bounds.dddq += w * w * rho;
  }
  return bounds;
}

JointLog trajectory_log(const FourierSeries& series, double duration, double rate_hz, const Model& model) {
  return sampled_joint_log([&](double t) { return series.sample(t); }, duration, rate_hz, model, "Fourier excitation");
}

JointLog sampled_joint_log(const std::function<JointSample(double)>& sample, double duration, double rate_hz,
                           const Model& model, std::string source) {
  JointLog log;
  log.source = std::move(source);
  Data data;
  const auto samples = static_cast<long>(std::floor(duration * rate_hz + 1e-9));
  for (long k = 0; k <= samples; ++k) {
    const double t = static_cast<double>(k) / rate_hz;   // no accumulated rounding
    const JointSample s = sample(t);
    Vector7 tau;
    rnea(model, data, s.q, s.dq, s.ddq, tau);
    log.t.push_back(t);
    log.q.push_back(s.q);
    log.dq.push_back(s.dq);
    log.ddq.push_back(s.ddq);
    log.tau_J.push_back(tau + friction_torque(model.parameters().friction, s.dq));
  }
  return log;
}

}  // namespace csp::planners
