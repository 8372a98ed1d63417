// What the verdict leaves unexplained, localised: per joint, the held-out residual that is left is
// fitted by least squares with each kind of structure a real arm's torque error can have (a
// constant, a drift in time, a sinusoid in time or in the joint's position, dependence on the
// velocity's sign or value, on the direction of acceleration (a loop in residual vs velocity, i.e.
// hysteresis), on acceleration, on the torque level, or power above the excitation band). The kind
// that accounts for the largest share of the joint's mean square is reported when it is large
// enough. Periodic kinds search a frequency or period grid: the share is in-sample, so the grid is
// coarse enough (a few hundred points over 1000 samples) that noise alone gets a share of a few %.
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>

#include "csp/gap/diagnosis.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp::gap {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

struct Candidate {
  std::string kind;
  double share = 0.0, size = 0.0, value = 0.0;
};

// Share of |r|^2 the least-squares fit of the columns of A removes, and the fit's coefficients.
double fitted_share(const MatrixXd& A, const VectorXd& r, VectorXd& coefficients) {
  coefficients = A.colPivHouseholderQr().solve(r);
  return 1.0 - (r - A * coefficients).squaredNorm() / std::max(r.squaredNorm(), 1e-300);
}

void consider(std::vector<Candidate>& out, const std::string& kind, double share, double mean_square, double value) {
  out.push_back({kind, share, std::sqrt(std::max(share, 0.0) * mean_square), value});
}

// The best sinusoid a sin(2 pi x / p) + b cos(2 pi x / p) over a log-spaced grid of p.
void best_sinusoid(std::vector<Candidate>& out, const std::string& kind, const VectorXd& x, const VectorXd& r,
                   double shortest, double longest, int grid, double mean_square, bool as_frequency) {
  double best_share = 0.0, best_period = shortest;
  MatrixXd A(x.size(), 2);
  VectorXd c;
  for (int g = 0; g <= grid; ++g) {
    const double p = shortest * std::pow(longest / shortest, static_cast<double>(g) / grid);
    A.col(0) = (2.0 * M_PI * x / p).array().sin();
    A.col(1) = (2.0 * M_PI * x / p).array().cos();
    const double share = fitted_share(A, r, c);
    if (share > best_share) best_share = share, best_period = p;
  }
  consider(out, kind, best_share, mean_square, as_frequency ? 1.0 / best_period : best_period);
}

// Fraction of the series' power above 5 Hz (the excitation band ends at about 2 Hz).
double high_frequency_share(const VectorXd& r, double sample_period) {
  Eigen::FFT<double> fft;
  std::vector<double> series(r.data(), r.data() + r.size());
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, series);
  double high = 0.0, total = 0.0;
  const std::size_t n = series.size();
  for (std::size_t f = 0; f <= n / 2; ++f) {
    const double hz = static_cast<double>(f) / (static_cast<double>(n) * sample_period);
    total += std::norm(spectrum[f]);
    if (hz > kBandEdges.back()) high += std::norm(spectrum[f]);
  }
  return total > 0.0 ? high / total : 0.0;
}

// A residual periodic in time at a frequency the motion itself has is no vibration: it follows the
// motion (a motion-dependent torque the model lacks). Whether a joint's velocity has at least
// kMotionShare of its variance in a sinusoid at `frequency` (over a short part the frequency
// resolution is coarse, so which joint is not told).
constexpr double kMotionShare = 0.1;
bool motion_at(const Samples& s, const VectorXd& t, double frequency) {
  const auto n = t.size();
  MatrixXd A(n, 2);
  A.col(0) = (2.0 * M_PI * frequency * t).array().sin();
  A.col(1) = (2.0 * M_PI * frequency * t).array().cos();
  const auto qr = A.colPivHouseholderQr();
  for (int i = 0; i < kNumJoints; ++i) {
    VectorXd dq(n);
    for (Eigen::Index k = 0; k < n; ++k) dq[k] = s.dq[static_cast<std::size_t>(k)][i];
    dq.array() -= dq.mean();
    const double share = 1.0 - (dq - A * qr.solve(dq)).squaredNorm() / std::max(dq.squaredNorm(), 1e-300);
    if (share >= kMotionShare) return true;
  }
  return false;
}

// The library effect a kind of structure belongs to, or "" when none models it.
std::string library_effect_of(const std::string& kind) {
  if (kind == "offset") return "sensor_offset";
  if (kind == "time_drift") return "thermal_drift";
  if (kind == "position_periodic") return "position_ripple";
  if (kind == "velocity_sign" || kind == "velocity") return "joint_friction";
  if (kind == "hysteresis") return "friction_hysteresis";
  if (kind == "acceleration") return "armature";
  if (kind == "torque_level") return "sensor_gain";
  return "";
}

std::string describe(const UnexplainedStructure& u, const std::vector<std::string>& causes) {
  const int j = u.joint;
  std::string what;
  if (u.kind == "offset") what = format("a constant %.3f N m", u.value);
  if (u.kind == "time_drift") what = format("a drift of %.3f N m per minute", u.value);
  if (u.kind == "time_periodic") what = format("periodic in time at %.2f Hz", u.value);
  if (u.kind == "motion_periodic")
    what = format("periodic in time at %.2f Hz, a frequency the motion has: a torque that follows the motion, not "
                  "a vibration", u.value);
  if (u.kind == "position_periodic") what = format("periodic in q%d with period %.3f rad", j, u.value);
  if (u.kind == "velocity_sign") what = format("a step with the sign of dq%d (%.3f N m)", j, u.value);
  if (u.kind == "velocity") what = format("proportional to dq%d (%.3f N m s/rad)", j, u.value);
  if (u.kind == "hysteresis")
    what = format("a loop against dq%d: %.3f N m between accelerating and decelerating", j, u.value);
  if (u.kind == "acceleration") what = format("proportional to ddq%d (%.4f kg m^2)", j, u.value);
  if (u.kind == "torque_level") what = format("proportional to the model torque (%.1f %%)", 100.0 * u.value);
  if (u.kind == "high_frequency") what = "above 5 Hz (vibration or noise the model cannot have)";
  const std::string effect = library_effect_of(u.kind);
  std::string tail = "no library effect";
  if (!effect.empty())
    tail = std::find(causes.begin(), causes.end(), effect) != causes.end()
               ? "left after " + effect + " was fitted"
               : "like " + effect + ", which was not significant over the whole arm";
  return format("joint %d: %.3f N m (%.0f %% of what is left) %s; %s", j, u.size, 100.0 * u.share, what.c_str(),
                tail.c_str());
}

}  // namespace

std::vector<UnexplainedStructure> localise_unexplained(const Part& part, const VectorXd& left,
                                                       const std::vector<std::string>& causes) {
  std::vector<UnexplainedStructure> found;
  const Samples& s = part.samples;
  const auto n = static_cast<Eigen::Index>(s.size());
  if (n < 16) return found;
  const double sample_period = (s.t.back() - s.t.front()) / static_cast<double>(n - 1);
  VectorXd t(n), ones = VectorXd::Ones(n);
  for (Eigen::Index k = 0; k < n; ++k) t[k] = s.t[static_cast<std::size_t>(k)];
  for (int j = 0; j < kNumJoints; ++j) {
    VectorXd r(n), q(n), dq(n), ddq(n), tau(n), sign(n), accelerating(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(k);
      r[k] = left[kNumJoints * k + j], q[k] = s.q[i][j], dq[k] = s.dq[i][j], ddq[k] = s.ddq[i][j];
      tau[k] = part.predicted[i][j], sign[k] = smooth_sign(dq[k]);
      accelerating[k] = std::tanh(ddq[k] * dq[k] / 0.01);  // speeding up (+1) or slowing down (-1) ...
      accelerating[k] *= sign[k];                          // ... signed with the motion: the loop's branch
    }
    const double mean_square = r.squaredNorm() / static_cast<double>(n);
    std::vector<Candidate> candidates;
    // One regressor column; `value` turns its coefficient into the reported parameter.
    auto fit_column = [&](const char* kind, const VectorXd& column, double value_per_coefficient) {
      VectorXd c;
      const double share = fitted_share(column, r, c);
      consider(candidates, kind, share, mean_square, value_per_coefficient * c[0]);
    };
    fit_column("offset", ones, 1.0);
    fit_column("time_drift", t.array() - t.mean(), 60.0);
    best_sinusoid(candidates, "time_periodic", t, r, 1.0 / 20.0, 1.0 / 0.05, 300, mean_square, true);
    best_sinusoid(candidates, "position_periodic", q, r, 0.03, 2.0, 300, mean_square, false);
    fit_column("velocity_sign", sign, 2.0);
    fit_column("velocity", dq, 1.0);
    fit_column("hysteresis", accelerating, 2.0);
    fit_column("acceleration", ddq, 1.0);
    fit_column("torque_level", tau, 1.0);
    consider(candidates, "high_frequency", high_frequency_share(r, sample_period), mean_square, 0.0);
    Candidate best = *std::max_element(candidates.begin(), candidates.end(),
                                       [](const Candidate& a, const Candidate& b) { return a.share < b.share; });
    if (best.share < kUnexplainedShare || best.size < kUnexplainedSize) continue;
    if (best.kind == "time_periodic" && motion_at(s, t, best.value)) best.kind = "motion_periodic";
    UnexplainedStructure u{j + 1, best.kind, best.size, best.share, best.value, ""};
    u.detail = describe(u, causes);
    found.push_back(u);
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.size > b.size; });
  return found;
}

}  // namespace csp::gap
