#include "csp/gap/signal.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "csp/io/svg_plot.hpp"   // format

namespace csp::gap {

SavitzkyGolay::SavitzkyGolay(int half_width, int order, double dt) : half_width_(half_width) {
  // Vandermonde matrix of the window; row r of its pseudo-inverse maps the points to the
  // coefficient of x^r, so row 0 is the value at the centre and row 1 / dt the derivative.
  const int n = 2 * half_width + 1;
  Eigen::MatrixXd vandermonde(n, order + 1);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r <= order; ++r) vandermonde(i, r) = std::pow(static_cast<double>(i - half_width), r);
  const Eigen::MatrixXd pseudo_inverse = vandermonde.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(n, n));
  value_weights_ = pseudo_inverse.row(0).transpose();
  derivative_weights_ = pseudo_inverse.row(1).transpose() / dt;
}

Vector7 SavitzkyGolay::apply(const std::vector<Vector7>& series, std::size_t centre, int derivative) const {
  const Eigen::VectorXd& w = derivative == 0 ? value_weights_ : derivative_weights_;
  Vector7 sum = Vector7::Zero();
  for (int i = 0; i < w.size(); ++i) sum += w[i] * series[centre - half_width_ + i];
  return sum;
}

double SavitzkyGolay::noise_spectrum(int derivative, std::size_t stride, double frequency) const {
  const Eigen::VectorXd& w = derivative == 0 ? value_weights_ : derivative_weights_;
  double density = 0.0;
  for (Eigen::Index lag = 0; lag < w.size(); lag += static_cast<Eigen::Index>(stride)) {
    const double r = w.head(w.size() - lag).dot(w.tail(w.size() - lag));
    const double m = static_cast<double>(lag / static_cast<Eigen::Index>(stride));
    density += (lag == 0 ? 1.0 : 2.0) * r * std::cos(2.0 * M_PI * frequency * m);
  }
  return density;
}

namespace {

// Linear interpolation of `series` (at times t) onto the grid t0 + k dt, k = 0..n-1.
std::vector<Vector7> resample(const std::vector<double>& t, const std::vector<Vector7>& series, double dt,
                              std::size_t n) {
  std::vector<Vector7> out(n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double ti = t.front() + static_cast<double>(i) * dt;
    while (k + 2 < t.size() && t[k + 1] < ti) ++k;
    const double a = std::clamp((ti - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0);
    out[i] = (1.0 - a) * series[k] + a * series[k + 1];
  }
  return out;
}

}  // namespace

double check_time_steps(const JointLog& log, const FilterOptions& options) {
  if (log.size() < 2) throw JointLogError(log.source + ": expected at least 2 rows, got " + std::to_string(log.size()));
  // A step longer than the filter's window would be bridged by a straight line the filter takes
  // for motion: a gap in the recording (a pause, two logs joined), not samples of one motion.
  std::size_t widest = 0;
  std::vector<double> steps(log.size() - 1);
  for (std::size_t k = 0; k + 1 < log.size(); ++k) {
    steps[k] = log.t[k + 1] - log.t[k];
    if (steps[k] > steps[widest]) widest = k;
  }
  if (steps[widest] > options.window)
    throw JointLogError(log.source + ": the time jumps by " + format("%g", steps[widest]) + " s from t = " +
                        format("%g", log.t[widest]) + " s to " + format("%g", log.t[widest + 1]) +
                        " s, more than the smoothing filter's window (" + format("%g", options.window) +
                        " s): a gap in the recording, which the filter would bridge with a straight line; give the "
                        "log without it (one log per stretch of recording)");
  // Grid spacing: the median time step (robust to the jitter and gaps of real logs).
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  const double dt = steps[steps.size() / 2];
  // The grid holds about one point per row when the steps are about even; many more means most
  // steps are far shorter than the others (rows bunched in time), which no robot's log is.
  const double points = std::floor((log.t.back() - log.t.front()) / dt) + 1;
  if (points > 4.0 * static_cast<double>(log.size()))
    throw JointLogError(log.source + ": the time steps are too uneven for a uniform grid: at the median step of " +
                        format("%g", dt) + " s the " + std::to_string(log.size()) + " rows span " +
                        format("%.0f", points) + " grid points (more than 4 per row)");
  return dt;
}

Samples filter_log(const JointLog& log, const FilterOptions& options) {
  const double dt = check_time_steps(log, options);
  const std::size_t n = static_cast<std::size_t>(std::floor((log.t.back() - log.t.front()) / dt)) + 1;
  const int half_width = std::max(options.order / 2 + 1, static_cast<int>(std::lround(0.5 * options.window / dt)));
  const std::size_t stride =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(options.sample_period / dt)));
  const std::size_t needed = 2 * static_cast<std::size_t>(half_width) + 1 + 10 * stride;
  if (n < needed)
    throw JointLogError(log.source + ": too short for the smoothing filter: " + std::to_string(n) +
                        " samples on the uniform grid, need at least " + std::to_string(needed) + " (" +
                        std::to_string(options.window) + " s window plus 10 samples)");

  const std::vector<Vector7> q = resample(log.t, log.q, dt, n), dq = resample(log.t, log.dq, dt, n),
                             tau = resample(log.t, log.tau_J, dt, n);
  const std::vector<Vector7> ddq = log.ddq.empty() ? std::vector<Vector7>{} : resample(log.t, log.ddq, dt, n);
  const auto filter = std::make_shared<const SavitzkyGolay>(half_width, options.order, dt);

  Samples s;
  s.source = log.source;
  for (std::size_t k = half_width; k + half_width < n; k += stride) {
    s.t.push_back(log.t.front() + static_cast<double>(k) * dt);
    s.q.push_back(filter->apply(q, k, 0));
    s.dq.push_back(filter->apply(dq, k, 0));
    s.ddq.push_back(ddq.empty() ? filter->apply(dq, k, 1) : filter->apply(ddq, k, 0));
    s.tau.push_back(filter->apply(tau, k, 0));
    s.dtau.push_back(filter->apply(tau, k, 1));
    s.grid_index.push_back(k);
  }
  s.grid_q = q, s.grid_dq = dq, s.filter = filter, s.stride = stride, s.ddq_differentiated = ddq.empty();
  return s;
}

std::vector<Vector7> Samples::smoothed(const std::vector<Vector7>& grid_series) const {
  std::vector<Vector7> out(grid_index.size());
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = filter->apply(grid_series, grid_index[k], 0);
  return out;
}

}  // namespace csp::gap
