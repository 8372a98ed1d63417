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
// textbook sigma uses too; the step scaled by sqrt(B / (B - 1)), as a mean over B resampled blocks
// has (B - 1) / B of its variance. `jacobian` is the fitted torque's at theta (stacked, 7 rows per
// sample), `left` the residual the fit leaves there. Deterministic for a seed.
struct ParameterReplicates {
  std::vector<Eigen::VectorXd> theta;
  // Directions of theta the whole part does not determine (the torque does not change along them),
  // each scaled to a largest element of 1: a value that moves along one has no interval.
  std::vector<Eigen::VectorXd> undetermined;
};
ParameterReplicates bootstrap_parameters(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& left,
                                         const std::vector<int>& blocks, const Eigen::VectorXd& theta, unsigned seed,
                                         int replicates = kBootstrapReplicates);

// The interval of a held-out figure: the mean square of `left` over `before`'s (stacked on the same
// samples), with the samples' blocks drawn with replacement (never below zero).
std::array<double, 2> bootstrap_fraction(const Eigen::VectorXd& left, const Eigen::VectorXd& before,
                                         const std::vector<int>& blocks, unsigned seed,
                                         int replicates = kBootstrapReplicates);

// The kIntervalLevel interval from bootstrap replicates over `blocks` blocks: their percentiles at
// the tail of Student's t with B - 1 degrees of freedom instead of the normal's (for a mean over B
// blocks, Student's interval; percentiles, so an exp(theta) keeps its skew and its sign). The
// replicates carry the sqrt(B / (B - 1)) of the resampled variance already. NaN with fewer than
// kMinBlocks blocks or a replicate that is not finite.
std::array<double, 2> bootstrap_interval(std::vector<double> replicates, int blocks);
// Their standard deviation; NaN as above.
double bootstrap_sigma(const std::vector<double>& replicates, int blocks);

// To every number or list of numbers of `point` (an effect's describe()), adds KEY_sigma and
// KEY_interval ([low, high], or one per element) from the same key of each replicate's description
// over `blocks` blocks; null where there is none: too few blocks, or a value that differs in one of
// the descriptions `moved` (theta moved a little along each undetermined direction).
void add_intervals(nlohmann::json& point, const std::vector<nlohmann::json>& replicates, int blocks,
                   const std::vector<nlohmann::json>& moved = {});

// Whether every number of a description (and of its lists) is finite.
bool all_finite(const nlohmann::json& description);
// point + factor (moved - point) for every number and list of numbers of a description; the rest as
// in `point`. With moved the description at theta + step / factor: the first-order one at theta + step.
nlohmann::json extrapolate(const nlohmann::json& point, const nlohmann::json& moved, double factor);

}  // namespace csp::gap
