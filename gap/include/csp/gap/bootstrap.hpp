// Uncertainty of a fit by the moving-block bootstrap (Kuensch 1989): the residual samples of a log
// are correlated (the smoothing filter, the model's input noise, slow misfit), so the textbook
// sigma^2 (J^T J)^-1 of white residuals is too narrow; resampling whole blocks of the log keeps
// what happens within a block together (docs/gap.md, "Uncertainty").
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "csp/gap/signal.hpp"

namespace csp::gap {

inline constexpr double kBootstrapBlock = 0.5;   // [s] five filter windows: the filtered noise forgets in one
inline constexpr int kBootstrapReplicates = 200; // the usual count for standard deviations and 95 % intervals
inline constexpr double kIntervalLevel = 0.95;
inline constexpr int kMinBlocks = 4;              // fewer (a part under 2 s): no interval

// Each sample's block: consecutive stretches of `length` seconds of the log's time, numbered from 0
// without gaps (a part with samples left out has fewer blocks).
std::vector<int> time_blocks(const Samples& samples, double length = kBootstrapBlock);

// The one-step block bootstrap of a fit (Davidson and MacKinnon 1999): each replicate draws the
// blocks of the part it was fitted on with replacement and takes one Gauss-Newton step from the fit
// `theta` on them: exact for the parameters of linear effects, for the others the linearisation the
// textbook sigma uses too. `jacobian` is the fitted torque's at theta (stacked, 7 rows per sample),
// `left` the residual the fit leaves there. A parameter the whole part does not determine is NaN in
// every replicate. Deterministic for a seed.
std::vector<Eigen::VectorXd> bootstrap_parameters(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& left,
                                                  const std::vector<int>& blocks, const Eigen::VectorXd& theta,
                                                  unsigned seed, int replicates = kBootstrapReplicates);

// The interval of a held-out figure: the mean square of `left` over `before`'s (stacked on the same
// samples), with the samples' blocks drawn with replacement.
std::array<double, 2> bootstrap_fraction(const Eigen::VectorXd& left, const Eigen::VectorXd& before,
                                         const std::vector<int>& blocks, unsigned seed,
                                         int replicates = kBootstrapReplicates);

// The kIntervalLevel interval of an estimate from its bootstrap replicates over `blocks` blocks: the
// replicates' central percentile interval, widened about the estimate for the few blocks a short
// part has (the percentile interval of a mean over B blocks is the normal interval with the
// variance's (B - 1) / B; widened by sqrt(B / (B - 1)) t_{B-1} / z it is Student's for B blocks).
// NaN with fewer than kMinBlocks blocks or a replicate that is not finite.
std::array<double, 2> bootstrap_interval(std::vector<double> replicates, double estimate, int blocks);
// Their standard deviation, with the same (B - 1) / B undone; NaN as above.
double bootstrap_sigma(const std::vector<double>& replicates, int blocks);

// To every number or list of numbers of `point` (an effect's describe()), adds KEY_sigma and
// KEY_interval ([low, high], or one per element) from the same key of each replicate's description
// over `blocks` blocks; null where there is none (a parameter not identified, too few blocks).
void add_intervals(nlohmann::json& point, const std::vector<nlohmann::json>& replicates, int blocks);

}  // namespace csp::gap
