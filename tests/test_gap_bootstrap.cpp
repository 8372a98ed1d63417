// The block bootstrap of gap/ (docs/gap.md, "Uncertainty") against a Monte Carlo truth: the spread
// of least-squares estimates over many independent draws of correlated noise.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <random>

#include "csp/gap/bootstrap.hpp"

namespace csp::gap {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A linear fit of the gap's shape: 7 rows per sample at 100 Hz, three parameters (a constant, a slow
// sinusoid, a line in time, the last in other units), and correlated noise: white noise through a
// moving average of 10 samples per joint, as the smoothing filter (0.1 s) leaves a sensor's noise.
struct CorrelatedProblem {
  static constexpr int kSamples = 3000, kAverage = 10;
  static constexpr double kPeriod = 0.01, kNoise = 0.1;
  Samples samples;
  MatrixXd regressor = MatrixXd(kNumJoints * kSamples, 3);
  VectorXd truth = (VectorXd(3) << 0.3, -0.2, 50.0).finished();

  CorrelatedProblem() {
    std::mt19937_64 engine(7);
    std::normal_distribution<double> gain(1.0, 0.3);
    Vector7 g0, g1, g2;
    for (int j = 0; j < kNumJoints; ++j) g0[j] = gain(engine), g1[j] = gain(engine), g2[j] = gain(engine);
    for (int k = 0; k < kSamples; ++k) {
      const double t = k * kPeriod;
      samples.t.push_back(t);
      for (int j = 0; j < kNumJoints; ++j) {
        const Eigen::Index row = kNumJoints * k + j;
        regressor(row, 0) = g0[j];
        regressor(row, 1) = g1[j] * std::sin(2.0 * M_PI * 0.3 * t);
        regressor(row, 2) = g2[j] * 1e-3 * t;
      }
    }
  }
  VectorXd measurement(std::mt19937_64& engine) const {
    std::normal_distribution<double> normal(0.0, kNoise);
    const Eigen::Index rows = regressor.rows();
    VectorXd white(rows + kNumJoints * kAverage), noise = VectorXd::Zero(rows);
    for (double& w : white) w = normal(engine);
    for (int lag = 0; lag < kAverage; ++lag) noise += white.segment(kNumJoints * lag, rows) / std::sqrt(double(kAverage));
    return regressor * truth + noise;
  }
};

double standard_deviation(const std::vector<double>& v) {
  double mean = 0.0, square = 0.0;
  for (double x : v) mean += x / static_cast<double>(v.size());
  for (double x : v) square += (x - mean) * (x - mean);
  return std::sqrt(square / static_cast<double>(v.size() - 1));
}

// The textbook sigma of white residuals is several times too narrow on correlated noise; the block
// bootstrap's matches the estimates' true spread and its 95 % intervals cover the truth.
TEST(GapBootstrap, MatchesTheSpreadOfEstimatesOnCorrelatedNoiseWhereTheWhiteSigmaDoesNot) {
  const CorrelatedProblem problem;
  const std::vector<int> blocks = time_blocks(problem.samples);
  ASSERT_EQ(blocks.back() + 1, 60) << "30 s in blocks of 0.5 s";
  const Eigen::ColPivHouseholderQR<MatrixXd> qr(problem.regressor);
  const MatrixXd white_covariance = (problem.regressor.transpose() * problem.regressor).inverse();
  std::mt19937_64 engine(11);
  constexpr int kDraws = 300, kBootstrapped = 40;
  std::array<std::vector<double>, 3> estimates;
  Eigen::Vector3d bootstrap_sigma = Eigen::Vector3d::Zero(), white_sigma = Eigen::Vector3d::Zero();
  int covered = 0;
  for (int draw = 0; draw < kDraws; ++draw) {
    const VectorXd y = problem.measurement(engine);
    const VectorXd theta = qr.solve(y);
    for (int i = 0; i < 3; ++i) estimates[i].push_back(theta[i]);
    if (draw >= kBootstrapped) continue;
    const VectorXd left = y - problem.regressor * theta;
    const double variance = left.squaredNorm() / static_cast<double>(left.size() - 3);
    const ParameterReplicates replicates =
        bootstrap_parameters(problem.regressor, left, blocks, theta, static_cast<unsigned>(draw));
    ASSERT_EQ(replicates.theta.size(), static_cast<std::size_t>(kBootstrapReplicates));
    EXPECT_TRUE(replicates.undetermined.empty());
    for (int i = 0; i < 3; ++i) {
      std::vector<double> values;
      for (const VectorXd& r : replicates.theta) values.push_back(r[i]);
      bootstrap_sigma[i] += gap::bootstrap_sigma(values, 60) / kBootstrapped;
      white_sigma[i] += std::sqrt(variance * white_covariance(i, i)) / kBootstrapped;
      const std::array<double, 2> interval = bootstrap_interval(values, 60);
      covered += interval[0] <= problem.truth[i] && problem.truth[i] <= interval[1];
    }
  }
  for (int i = 0; i < 3; ++i) {
    const double spread = standard_deviation(estimates[i]);
    std::cout << "parameter " << i << ": estimates' spread " << spread << ", block bootstrap sigma "
              << bootstrap_sigma[i] << " (" << bootstrap_sigma[i] / spread << "x), white sigma " << white_sigma[i]
              << " (" << white_sigma[i] / spread << "x)\n";
    EXPECT_GT(bootstrap_sigma[i] / spread, 0.75) << i;
    EXPECT_LT(bootstrap_sigma[i] / spread, 1.25) << i;
    EXPECT_LT(white_sigma[i] / spread, 0.5) << i << ": the white sigma was to be too narrow here";
  }
  std::cout << "95 % intervals covering the truth: " << covered << " of " << 3 * kBootstrapped << "\n";
  EXPECT_GE(covered, static_cast<int>(0.85 * 3 * kBootstrapped));
}

// A direction the data do not determine is found, and a value that moves along it gets no interval
// (null in the JSON) while a combination the data do determine gets one; add_intervals leaves what is
// not a fitted number (counts, names, flags) alone.
TEST(GapBootstrap, AValueTheDataDoNotDetermineGetsNoIntervalACombinationTheyDoGetsOne) {
  CorrelatedProblem problem;
  MatrixXd regressor(problem.regressor.rows(), 4);
  regressor << problem.regressor, problem.regressor.col(0) * 2.0;  // the torque sees theta_0 + 2 theta_3 only
  std::mt19937_64 engine(3);
  const VectorXd y = problem.measurement(engine);
  VectorXd theta(4);
  theta << regressor.leftCols(3).colPivHouseholderQr().solve(y), 0.0;
  const ParameterReplicates replicates =
      bootstrap_parameters(regressor, y - regressor * theta, time_blocks(problem.samples), theta, 1);
  ASSERT_EQ(replicates.undetermined.size(), 1u);
  const VectorXd& direction = replicates.undetermined[0];
  EXPECT_NEAR(direction.cwiseAbs().maxCoeff(), 1.0, 1e-12);
  EXPECT_NEAR(direction[0] + 2.0 * direction[3], 0.0, 1e-9) << direction.transpose();
  EXPECT_NEAR(direction[1], 0.0, 1e-9);
  auto describe = [](const VectorXd& t) {
    return nlohmann::json{{"count", 4},           {"names", {"a", "b"}},  {"flag", true},
                          {"sum_Nm", t[0] + t[3]}, {"seen_Nm", t[0] + 2.0 * t[3]}, {"values", {t[1], t[2]}}};
  };
  nlohmann::json point = describe(theta);
  std::vector<nlohmann::json> described, moved = {describe(theta + 1e-6 * direction)};
  for (const VectorXd& r : replicates.theta) described.push_back(describe(r));
  add_intervals(point, described, 60, moved);
  EXPECT_TRUE(point.at("sum_Nm_sigma").is_null());
  EXPECT_TRUE(point.at("sum_Nm_interval").is_null());
  ASSERT_TRUE(point.at("seen_Nm_interval").is_array()) << point.dump();
  EXPECT_LT(point.at("seen_Nm_interval")[0].get<double>(), theta[0]);
  EXPECT_GT(point.at("seen_Nm_interval")[1].get<double>(), theta[0]);
  ASSERT_EQ(point.at("values_interval").size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const double low = point.at("values_interval")[i][0], high = point.at("values_interval")[i][1];
    EXPECT_LT(low, theta[i + 1]);
    EXPECT_GT(high, theta[i + 1]);
    EXPECT_GT(point.at("values_sigma")[i].get<double>(), 0.0);
  }
  for (const char* untouched : {"count_sigma", "names_sigma", "flag_sigma", "count_interval"})
    EXPECT_FALSE(point.contains(untouched)) << untouched;
}

// The held-out figure's interval: exact for a residual left in proportion everywhere, and half as
// wide on four times the samples (the square-root law of a mean over independent blocks).
TEST(GapBootstrap, HeldOutFractionIntervalIsExactForAProportionAndNarrowsAsTheSquareRoot) {
  CorrelatedProblem problem;
  std::mt19937_64 engine(5);
  const VectorXd before = problem.measurement(engine) - problem.regressor * problem.truth;
  const std::vector<int> blocks = time_blocks(problem.samples);
  const std::array<double, 2> proportional = bootstrap_fraction(0.5 * before, before, blocks, 1);
  EXPECT_NEAR(proportional[0], 0.25, 1e-12);
  EXPECT_NEAR(proportional[1], 0.25, 1e-12);

  // `before` and `left` independent noises (the latter of half the level): the fraction's estimate scatters.
  const VectorXd left = 0.5 * (problem.measurement(engine) - problem.regressor * problem.truth);
  auto width = [&](int samples) {
    Samples first;
    first.t.assign(problem.samples.t.begin(), problem.samples.t.begin() + samples);
    const std::array<double, 2> interval = bootstrap_fraction(
        left.head(kNumJoints * samples), before.head(kNumJoints * samples), time_blocks(first), 2, 2000);
    return interval[1] - interval[0];
  };
  const double ratio = width(CorrelatedProblem::kSamples) / width(CorrelatedProblem::kSamples / 4);
  std::cout << "interval width on 30 s over that on its first 7.5 s: " << ratio << "\n";
  EXPECT_GT(ratio, 0.5 * 0.7);
  EXPECT_LT(ratio, 0.5 * 1.4);
}

}  // namespace
}  // namespace csp::gap
