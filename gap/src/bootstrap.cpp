#include "csp/gap/bootstrap.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace csp::gap {

using Eigen::MatrixXd;
using Eigen::VectorXd;

std::vector<int> time_blocks(const Samples& samples, double length) {
  std::vector<int> blocks(samples.size());
  long previous = -1;
  int block = -1;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto stretch = static_cast<long>(std::floor((samples.t[k] - samples.t.front()) / length));
    if (stretch != previous) ++block, previous = stretch;
    blocks[k] = block;
  }
  return blocks;
}

namespace {

// Each sample's sum of squares over its 7 rows, added up per block.
std::vector<double> block_squares(const VectorXd& stacked, const std::vector<int>& blocks) {
  std::vector<double> out(blocks.empty() ? 0 : static_cast<std::size_t>(blocks.back() + 1), 0.0);
  for (std::size_t k = 0; k < blocks.size(); ++k)
    out[static_cast<std::size_t>(blocks[k])] += stacked.segment(kNumJoints * static_cast<Eigen::Index>(k), kNumJoints).squaredNorm();
  return out;
}

// How often each of `count` blocks is drawn in `count` draws with replacement.
std::vector<int> draw_blocks(std::size_t count, std::mt19937_64& engine) {
  std::vector<int> times(count, 0);
  std::uniform_int_distribution<std::size_t> pick(0, count - 1);
  for (std::size_t i = 0; i < count; ++i) ++times[pick(engine)];
  return times;
}

}  // namespace

std::vector<VectorXd> bootstrap_parameters(const MatrixXd& jacobian, const VectorXd& left, const std::vector<int>& blocks,
                                           const VectorXd& theta, unsigned seed, int replicates) {
  const Eigen::Index p = theta.size();
  if (p == 0 || blocks.empty()) return {};
  // Per block: J_b^T J_b and J_b^T r_b over its rows.
  const auto count = static_cast<std::size_t>(blocks.back() + 1);
  std::vector<MatrixXd> block_normal(count, MatrixXd::Zero(p, p));
  std::vector<VectorXd> block_gradient(count, VectorXd::Zero(p));
  for (std::size_t k = 0; k < blocks.size();) {
    std::size_t end = k;
    while (end < blocks.size() && blocks[end] == blocks[k]) ++end;
    const auto rows = Eigen::seqN(kNumJoints * static_cast<Eigen::Index>(k), kNumJoints * static_cast<Eigen::Index>(end - k));
    const auto b = static_cast<std::size_t>(blocks[k]);
    block_normal[b].noalias() += jacobian(rows, Eigen::all).transpose() * jacobian(rows, Eigen::all);
    block_gradient[b].noalias() += jacobian(rows, Eigen::all).transpose() * left(rows);
    k = end;
  }

  // Parameters in directions the whole part does not determine get no interval: the eigenvectors of
  // the scaled normal matrix D J^T J D (D = diag(J^T J)^-1/2: units do not matter) with eigenvalues
  // below 1e-10 of the largest, and the parameters with weight in them.
  MatrixXd normal = MatrixXd::Zero(p, p);
  for (const MatrixXd& n : block_normal) normal += n;
  const VectorXd diagonal = normal.diagonal();
  const VectorXd scale = diagonal.cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(scale.asDiagonal() * normal * scale.asDiagonal());
  const double largest = eigen.eigenvalues().maxCoeff();
  std::vector<bool> identified(static_cast<std::size_t>(p));
  for (Eigen::Index i = 0; i < p; ++i) {
    double weight = 0.0;
    for (Eigen::Index e = 0; e < p; ++e)
      if (eigen.eigenvalues()[e] < 1e-10 * largest) weight += eigen.eigenvectors()(i, e) * eigen.eigenvectors()(i, e);
    identified[static_cast<std::size_t>(i)] = diagonal[i] > 0.0 && weight < 1e-3;
  }

  std::vector<VectorXd> out;
  std::mt19937_64 engine(seed);
  for (int r = 0; r < replicates; ++r) {
    // One Gauss-Newton step on the drawn blocks, in the scaled coordinates (the tiny ridge: a
    // resample without a direction's excitation leaves it at the fit).
    MatrixXd resampled_normal = MatrixXd::Zero(p, p);
    VectorXd resampled_gradient = VectorXd::Zero(p);
    const std::vector<int> drawn = draw_blocks(count, engine);
    for (std::size_t b = 0; b < count; ++b)
      if (drawn[b] > 0) resampled_normal += drawn[b] * block_normal[b], resampled_gradient += drawn[b] * block_gradient[b];
    MatrixXd scaled = scale.asDiagonal() * resampled_normal * scale.asDiagonal();
    scaled.diagonal().array() += 1e-10 * std::max(1.0, scaled.diagonal().maxCoeff());
    VectorXd replicate = theta + scale.cwiseProduct(scaled.ldlt().solve(scale.cwiseProduct(resampled_gradient)));
    for (Eigen::Index i = 0; i < p; ++i)
      if (!identified[static_cast<std::size_t>(i)]) replicate[i] = std::numeric_limits<double>::quiet_NaN();
    out.push_back(replicate);
  }
  return out;
}

std::array<double, 2> bootstrap_fraction(const VectorXd& left, const VectorXd& before, const std::vector<int>& blocks,
                                         unsigned seed, int replicates) {
  const std::vector<double> left_squares = block_squares(left, blocks), before_squares = block_squares(before, blocks);
  std::mt19937_64 engine(seed);
  std::vector<double> fractions;
  for (int r = 0; r < replicates && !left_squares.empty(); ++r) {
    const std::vector<int> drawn = draw_blocks(left_squares.size(), engine);
    double numerator = 0.0, denominator = 0.0;
    for (std::size_t b = 0; b < drawn.size(); ++b)
      numerator += drawn[b] * left_squares[b], denominator += drawn[b] * before_squares[b];
    fractions.push_back(numerator / std::max(denominator, std::numeric_limits<double>::min()));
  }
  const double estimate = left.squaredNorm() / std::max(before.squaredNorm(), std::numeric_limits<double>::min());
  return bootstrap_interval(fractions, estimate, static_cast<int>(left_squares.size()));
}

namespace {

// Student's t quantile by the Cornish-Fisher expansion about the normal one (Abramowitz and Stegun
// 26.7.5, three terms): 3.15 for the exact 3.18 at 3 degrees of freedom, within 1e-3 from 10 on.
double student_t_quantile(double z, int nu) {
  const double v = nu, z2 = z * z;
  return z + z * (z2 + 1.0) / (4.0 * v) + z * ((5.0 * z2 + 16.0) * z2 + 3.0) / (96.0 * v * v) +
         z * (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) / (384.0 * v * v * v);
}

bool usable(const std::vector<double>& replicates, int blocks) {
  if (blocks < kMinBlocks || replicates.size() < 2) return false;
  return std::all_of(replicates.begin(), replicates.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

std::array<double, 2> bootstrap_interval(std::vector<double> replicates, double estimate, int blocks) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!usable(replicates, blocks) || !std::isfinite(estimate)) return {nan, nan};
  std::sort(replicates.begin(), replicates.end());
  auto at = [&](double probability) {
    const double position = probability * static_cast<double>(replicates.size() - 1);
    const auto below = static_cast<std::size_t>(std::floor(position));
    const std::size_t above = std::min(below + 1, replicates.size() - 1);
    return replicates[below] + (position - std::floor(position)) * (replicates[above] - replicates[below]);
  };
  static_assert(kIntervalLevel == 0.95, "z below is the normal's 97.5 % point");
  const double tail = (1.0 - kIntervalLevel) / 2.0, z = 1.959963984540054;
  const double widen = std::sqrt(blocks / (blocks - 1.0)) * student_t_quantile(z, blocks - 1) / z;
  return {estimate + widen * (at(tail) - estimate), estimate + widen * (at(1.0 - tail) - estimate)};
}

double bootstrap_sigma(const std::vector<double>& replicates, int blocks) {
  if (!usable(replicates, blocks)) return std::numeric_limits<double>::quiet_NaN();
  double mean = 0.0, square = 0.0;
  for (double v : replicates) mean += v / static_cast<double>(replicates.size());
  for (double v : replicates) square += (v - mean) * (v - mean);
  return std::sqrt(square / static_cast<double>(replicates.size() - 1) * blocks / (blocks - 1.0));
}

namespace {

double number_or_nan(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

// One value's sigma and interval as JSON: numbers, or null where there are none.
std::pair<nlohmann::json, nlohmann::json> uncertainty(const std::vector<double>& replicates, double estimate, int blocks) {
  const double sigma = bootstrap_sigma(replicates, blocks);
  const std::array<double, 2> interval = bootstrap_interval(replicates, estimate, blocks);
  return {std::isfinite(sigma) ? nlohmann::json(sigma) : nlohmann::json(nullptr),
          std::isfinite(interval[0]) ? nlohmann::json{interval[0], interval[1]} : nlohmann::json(nullptr)};
}

}  // namespace

void add_intervals(nlohmann::json& point, const std::vector<nlohmann::json>& replicates, int blocks) {
  nlohmann::json added = nlohmann::json::object();
  std::vector<double> values(replicates.size());
  for (const auto& [key, value] : point.items()) {
    if (value.is_number_float()) {
      for (std::size_t r = 0; r < replicates.size(); ++r) values[r] = number_or_nan(replicates[r].at(key));
      std::tie(added[key + "_sigma"], added[key + "_interval"]) = uncertainty(values, value.get<double>(), blocks);
    } else if (value.is_array() && !value.empty() && value.front().is_number_float()) {
      nlohmann::json sigmas = nlohmann::json::array(), intervals = nlohmann::json::array();
      for (std::size_t i = 0; i < value.size(); ++i) {
        for (std::size_t r = 0; r < replicates.size(); ++r) values[r] = number_or_nan(replicates[r].at(key).at(i));
        const auto [sigma, interval] = uncertainty(values, number_or_nan(value.at(i)), blocks);
        sigmas.push_back(sigma), intervals.push_back(interval);
      }
      added[key + "_sigma"] = sigmas, added[key + "_interval"] = intervals;
    }
  }
  point.update(added);
}

}  // namespace csp::gap
