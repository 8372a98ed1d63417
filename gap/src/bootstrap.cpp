#include "csp/gap/bootstrap.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
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

ParameterReplicates bootstrap_parameters(const MatrixXd& jacobian, const VectorXd& left, const std::vector<int>& blocks,
                                         const VectorXd& theta, unsigned seed, int replicates) {
  const Eigen::Index p = theta.size();
  ParameterReplicates out;
  if (p == 0 || blocks.empty()) return out;
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

  // The directions the whole part does not determine: eigenvectors of the scaled normal matrix
  // D J^T J D (D = diag(J^T J)^-1/2, so units do not matter; a column whose diagonal is below 1e-12
  // of the largest counts as zero) with an eigenvalue below 1e-10 of the largest. A replicate steps
  // in the others only.
  MatrixXd normal = MatrixXd::Zero(p, p);
  for (const MatrixXd& n : block_normal) normal += n;
  const VectorXd diagonal = normal.diagonal();
  const double floor = 1e-12 * std::max(diagonal.maxCoeff(), std::numeric_limits<double>::min());
  const VectorXd scale = (diagonal.array() > floor).select(diagonal.cwiseMax(floor).cwiseSqrt().cwiseInverse(), 0.0);
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(scale.asDiagonal() * normal * scale.asDiagonal());
  const double largest = eigen.eigenvalues().maxCoeff();
  std::vector<Eigen::Index> determined;
  for (Eigen::Index e = 0; e < p; ++e)
    if (eigen.eigenvalues()[e] > 1e-10 * largest) determined.push_back(e);
  for (Eigen::Index i = 0; i < p; ++i)
    if (scale[i] == 0.0) out.undetermined.push_back(VectorXd::Unit(p, i));
  for (Eigen::Index e = 0; e < p; ++e)
    if (eigen.eigenvalues()[e] <= 1e-10 * largest && scale.cwiseProduct(eigen.eigenvectors().col(e)).norm() > 0.0) {
      const VectorXd direction = scale.cwiseProduct(eigen.eigenvectors().col(e));
      out.undetermined.push_back(direction / direction.cwiseAbs().maxCoeff());
    }
  const MatrixXd basis = scale.asDiagonal() * eigen.eigenvectors()(Eigen::all, determined);  // theta per coordinate

  // A mean over B blocks resampled has (B - 1) / B of its variance: the steps are scaled back.
  const double unbias = count > 1 ? std::sqrt(count / (count - 1.0)) : 1.0;
  std::mt19937_64 engine(seed);
  for (int r = 0; r < replicates; ++r) {
    // One Gauss-Newton step on the drawn blocks, within the determined directions.
    MatrixXd resampled_normal = MatrixXd::Zero(p, p);
    VectorXd resampled_gradient = VectorXd::Zero(p);
    const std::vector<int> drawn = draw_blocks(count, engine);
    for (std::size_t b = 0; b < count; ++b)
      if (drawn[b] > 0) resampled_normal += drawn[b] * block_normal[b], resampled_gradient += drawn[b] * block_gradient[b];
    const MatrixXd reduced = basis.transpose() * resampled_normal * basis;
    out.theta.push_back(theta + unbias * basis * reduced.ldlt().solve(basis.transpose() * resampled_gradient));
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
  const auto blocks_count = static_cast<double>(left_squares.size());
  for (double& f : fractions)  // (B - 1) / B of the variance, as bootstrap_parameters' steps
    f = std::max(0.0, estimate + std::sqrt(blocks_count / std::max(1.0, blocks_count - 1.0)) * (f - estimate));
  return bootstrap_interval(fractions, static_cast<int>(left_squares.size()));
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

std::array<double, 2> bootstrap_interval(std::vector<double> replicates, int blocks) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!usable(replicates, blocks)) return {nan, nan};
  std::sort(replicates.begin(), replicates.end());
  auto at = [&](double probability) {
    const double position = probability * static_cast<double>(replicates.size() - 1);
    const auto below = static_cast<std::size_t>(std::floor(position));
    const std::size_t above = std::min(below + 1, replicates.size() - 1);
    return replicates[below] + (position - std::floor(position)) * (replicates[above] - replicates[below]);
  };
  // The tail at Student's quantile for B blocks instead of the normal's: for a mean, Student's interval.
  static_assert(kIntervalLevel == 0.95, "z below is the normal's 97.5 % point");
  const double z = 1.959963984540054, t = student_t_quantile(z, blocks - 1);
  const double tail = 0.5 * std::erfc(t / std::sqrt(2.0));  // the normal's probability below -t
  return {at(tail), at(1.0 - tail)};
}

double bootstrap_sigma(const std::vector<double>& replicates, int blocks) {
  if (!usable(replicates, blocks)) return std::numeric_limits<double>::quiet_NaN();
  double mean = 0.0, square = 0.0;
  for (double v : replicates) mean += v / static_cast<double>(replicates.size());
  for (double v : replicates) square += (v - mean) * (v - mean);
  return std::sqrt(square / static_cast<double>(replicates.size() - 1));
}

namespace {

double number_or_nan(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

// One value's sigma and interval as JSON: numbers, or null where there are none.
// A value every replicate has alike does not depend on any direction the data determine (a parameter
// at the end of its grid, held there): no interval either.
std::pair<nlohmann::json, nlohmann::json> uncertainty(const std::vector<double>& replicates, int blocks) {
  const double sigma = bootstrap_sigma(replicates, blocks);
  if (!std::isfinite(sigma)) return {nullptr, nullptr};  // (finite: at least two replicates)
  const auto [lowest, highest] = std::minmax_element(replicates.begin(), replicates.end());
  if (*lowest == *highest) return {nullptr, nullptr};
  const std::array<double, 2> interval = bootstrap_interval(replicates, blocks);
  return {sigma, nlohmann::json{interval[0], interval[1]}};
}

}  // namespace

void add_intervals(nlohmann::json& point, const std::vector<nlohmann::json>& replicates, int blocks,
                   const std::vector<nlohmann::json>& moved) {
  // Whether a value of the point moves in one of the `moved` descriptions (beyond rounding).
  auto undetermined = [&](const std::string& key, std::optional<std::size_t> element) {
    const double value = number_or_nan(element ? point.at(key).at(*element) : point.at(key));
    return std::any_of(moved.begin(), moved.end(), [&](const nlohmann::json& m) {
      const double other = number_or_nan(element ? m.at(key).at(*element) : m.at(key));
      return !(std::abs(other - value) <= 1e-9 * std::max(1.0, std::abs(value)));
    });
  };
  nlohmann::json added = nlohmann::json::object();
  std::vector<double> values(replicates.size());
  const std::pair<nlohmann::json, nlohmann::json> none = {nullptr, nullptr};
  for (const auto& [key, value] : point.items()) {
    if (value.is_number_float()) {
      for (std::size_t r = 0; r < replicates.size(); ++r) values[r] = number_or_nan(replicates[r].at(key));
      std::tie(added[key + "_sigma"], added[key + "_interval"]) =
          undetermined(key, std::nullopt) ? none : uncertainty(values, blocks);
    } else if (value.is_array() && !value.empty() && value.front().is_number_float()) {
      nlohmann::json sigmas = nlohmann::json::array(), intervals = nlohmann::json::array();
      for (std::size_t i = 0; i < value.size(); ++i) {
        for (std::size_t r = 0; r < replicates.size(); ++r) values[r] = number_or_nan(replicates[r].at(key).at(i));
        const auto [sigma, interval] = undetermined(key, i) ? none : uncertainty(values, blocks);
        sigmas.push_back(sigma), intervals.push_back(interval);
      }
      added[key + "_sigma"] = sigmas, added[key + "_interval"] = intervals;
    }
  }
  point.update(added);
}

bool all_finite(const nlohmann::json& description) {
  for (const auto& [key, value] : description.items()) {
    if (value.is_number_float() && !std::isfinite(value.get<double>())) return false;
    if (value.is_array())
      for (const nlohmann::json& element : value)
        if (element.is_number_float() && !std::isfinite(element.get<double>())) return false;
  }
  return true;
}

nlohmann::json extrapolate(const nlohmann::json& point, const nlohmann::json& moved, double factor) {
  auto line = [factor](const nlohmann::json& a, const nlohmann::json& b) {
    return a.is_number_float() ? nlohmann::json(a.get<double>() + factor * (number_or_nan(b) - a.get<double>())) : a;
  };
  nlohmann::json out = point;
  for (const auto& [key, value] : point.items()) {
    if (value.is_number_float()) out[key] = line(value, moved.at(key));
    if (value.is_array())
      for (std::size_t i = 0; i < value.size(); ++i) out[key][i] = line(value[i], moved.at(key).at(i));
  }
  return out;
}

}  // namespace csp::gap
