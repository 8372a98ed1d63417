// What the verdict leaves unexplained, localised (docs/gap.md, "What stays unexplained").
// Per joint, the held-out residual that is left is first given its noise floor: the torque sensor's
// noise through the smoothing filter plus the model input's through the differentiator, each with
// its exact shape for white noise, scaled to its own side's spectrum above the excitation band.
// Structure is then sought above that floor, the strongest first and each on what the stronger ones
// left:
// - kinds fitted by least squares, each a shape a real arm's torque error can have (a constant, a
//   drift in time, a sinusoid in the joint's position, dependence on the velocity's sign or value, on
//   the direction of acceleration (a loop in residual vs velocity: hysteresis), on acceleration, on
//   the torque level): one counts when it captures kNoiseMargin times more than its best fit to any
//   of kSurrogates noise series with the floor's spectrum;
// - bands of the spectrum from 0.1 Hz to the Nyquist frequency standing above the floor (a line at a
//   fixed frequency, or power spread over a band, as a vibration whose amplitude follows the
//   configuration has), each with its side: the measured torque's or the model's.
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <random>

#include "csp/gap/diagnosis.hpp"
#include "csp/gap/spectrum.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp::gap {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kFloorAbove = kBandEdges.back();  // [Hz] the floor is measured above the excitation band
constexpr int kSurrogates = 19;                    // noise series per fitted kind
constexpr double kNoiseMargin = 3.0;               // times the best fit to noise
constexpr double kBandFalseAlarm = 1e-3;           // per joint: a noise bin passing the line threshold
constexpr double kBandEdgeRatio = 2.0;             // a band extends while its bins stay this far above the floor
constexpr double kLowestBand = 0.1;                // [Hz] below it, offset and time_drift describe the residual
constexpr double kLineShare = 0.8;                 // a band whose best sinusoid has this much of its power is a line

struct Candidate {
  std::string kind;
  double energy = 0.0;  // squared norm of the structure's torque over the samples [N^2 m^2]
  double noise = 0.0;   // what noise alone puts there on average, in the same units
  double value = 0.0, band_low = 0.0, band_high = 0.0;
  std::string side = kMeasuredTorque;
  int from_joint = 0;
  VectorXd torque;      // the structure's torque at the samples
};

// The fitted kinds of one joint: each a regressor column (its own motion's or torque's, or another
// joint's: a residual driven by joint j), or the sinusoid in position scanned over periods.
// `capture` is the least-squares fit's captured energy and the fitted torque.
struct Column {
  const char* kind;
  int from_joint;  // 1-based: the other joint whose torque, velocity or position it is; 0 = its own
};
class FittedKinds {
 public:
  FittedKinds(const MatrixXd& columns, std::vector<Column> names, const VectorXd& q)
      : columns_(columns), names_(std::move(names)) {
    // Position periods 0.03-2 rad, log spaced: sin and cos columns with their 2 x 2 Gram matrices.
    constexpr int kPeriods = 300;
    sin_.resize(q.size(), kPeriods + 1), cos_.resize(q.size(), kPeriods + 1);
    for (int g = 0; g <= kPeriods; ++g) {
      periods_.push_back(0.03 * std::pow(2.0 / 0.03, static_cast<double>(g) / kPeriods));
      sin_.col(g) = (2.0 * M_PI * q / periods_.back()).array().sin();
      cos_.col(g) = (2.0 * M_PI * q / periods_.back()).array().cos();
      Eigen::Matrix2d gram;
      gram << sin_.col(g).squaredNorm(), sin_.col(g).dot(cos_.col(g)), sin_.col(g).dot(cos_.col(g)),
          cos_.col(g).squaredNorm();
      gram_inverse_.push_back(gram.completeOrthogonalDecomposition().pseudoInverse());
    }
  }
  int count() const { return static_cast<int>(names_.size()) + 1; }
  Column name(int kind) const {
    return kind < static_cast<int>(names_.size()) ? names_[static_cast<std::size_t>(kind)] : Column{"position_periodic", 0};
  }

  // Kind `kind` fitted to r: the energy it captures, its parameter and torque.
  double capture(int kind, const VectorXd& r, double* value = nullptr, VectorXd* torque = nullptr) const {
    if (kind < static_cast<int>(names_.size())) {
      const auto column = columns_.col(kind);
      const double norm = std::max(column.squaredNorm(), 1e-300), coefficient = column.dot(r) / norm;
      if (value) *value = coefficient;
      if (torque) *torque = coefficient * column;
      return coefficient * column.dot(r);
    }
    const VectorXd s = sin_.transpose() * r, c = cos_.transpose() * r;
    double best = 0.0;
    int best_g = 0;
    for (Eigen::Index g = 0; g < s.size(); ++g) {
      const Eigen::Vector2d b(s[g], c[g]);
      const double energy = b.dot(gram_inverse_[static_cast<std::size_t>(g)] * b);
      if (energy > best) best = energy, best_g = static_cast<int>(g);
    }
    if (value) *value = periods_[static_cast<std::size_t>(best_g)];
    if (torque) {
      const Eigen::Vector2d ab =
          gram_inverse_[static_cast<std::size_t>(best_g)] * Eigen::Vector2d(s[best_g], c[best_g]);
      *torque = ab[0] * sin_.col(best_g) + ab[1] * cos_.col(best_g);
    }
    return best;
  }

 private:
  MatrixXd columns_, sin_, cos_;
  std::vector<Column> names_;
  std::vector<double> periods_;
  std::vector<Eigen::Matrix2d> gram_inverse_;
};

// sin(2 pi f t) and cos(2 pi f t), the columns of a sinusoid at `frequency` in time.
MatrixXd sinusoid_columns(const VectorXd& t, double frequency) {
  MatrixXd A(t.size(), 2);
  A.col(0) = (2.0 * M_PI * frequency * t).array().sin();
  A.col(1) = (2.0 * M_PI * frequency * t).array().cos();
  return A;
}

// A residual periodic in time at a frequency the motion itself has is no vibration: it follows the
// motion (a motion-dependent torque the model lacks). Whether a joint's velocity has at least
// kMotionShare of its variance in a sinusoid at `frequency` (over a short part the frequency
// resolution is coarse, so which joint is not told).
constexpr double kMotionShare = 0.1;
bool motion_at(const Samples& s, const VectorXd& t, double frequency) {
  const auto n = t.size();
  const MatrixXd A = sinusoid_columns(t, frequency);
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

// The least-squares sinusoid at `frequency` in time: its captured energy and torque.
double sinusoid_capture(const VectorXd& t, const VectorXd& r, double frequency, VectorXd& torque) {
  const MatrixXd A = sinusoid_columns(t, frequency);
  torque = A * A.colPivHouseholderQr().solve(r);
  return torque.dot(r);
}

// The bands of r's spectrum above the floor `level`: a bin more than ln(bins / kBandFalseAlarm)
// times the floor (noise passes it with probability kBandFalseAlarm over all bins: its bins are
// exponentially distributed) starts a band; it extends while the bins stay kBandEdgeRatio above.
// `measured` and `model` are the two sides' series, for the band's side.
std::vector<Candidate> bands(const VectorXd& r, const VectorXd& t, double sample_period,
                             const std::vector<double>& level, const VectorXd& measured, const VectorXd& model,
                             const Samples& samples) {
  std::vector<Candidate> found;
  const Periodogram p = periodogram(r, sample_period);
  const Periodogram fine = periodogram(r, sample_period, 4);  // resolution 1 / (4 T) for the peak
  const std::size_t first = std::max<std::size_t>(2, p.bin(kLowestBand)), last = p.power.size() - 1;
  const double start = std::log(static_cast<double>(last - first + 1) / kBandFalseAlarm);
  auto ratio = [&](std::size_t k) { return p.power[k] / std::max(level[k], 1e-300); };
  for (std::size_t k = first; k <= last; ++k) {
    if (ratio(k) <= start) continue;
    std::size_t low = k, high = k;
    while (low > first && ratio(low - 1) > kBandEdgeRatio) --low;
    while (high < last && ratio(high + 1) > kBandEdgeRatio) ++high;
    double band_noise = 0.0;
    for (std::size_t b = low; b <= high; ++b) band_noise += level[b];
    // The peak on the fine grid, then the best sinusoid within a quarter of a coarse bin of it.
    std::size_t peak = fine.bin(p.frequency(low));
    for (std::size_t b = peak; b <= fine.bin(p.frequency(high)); ++b)
      if (fine.power[b] > fine.power[peak]) peak = b;
    Candidate c;
    c.band_low = std::max(0.0, p.frequency(low) - 0.5 * p.bin_width);
    c.band_high = p.frequency(high) + 0.5 * p.bin_width;
    c.value = fine.frequency(peak);
    VectorXd line;
    double line_energy = 0.0;
    for (int step = -5; step <= 5; ++step) {
      const double f = fine.frequency(peak) + 0.05 * step * p.bin_width;
      VectorXd torque;
      const double energy = sinusoid_capture(t, r, f, torque);
      if (energy > line_energy) line_energy = energy, line = torque, c.value = f;
    }
    // The band's energy above the floor's, from its own part of r (the windowed periodogram weights
    // the middle of the series: a structure there would look larger than it is).
    const auto n = static_cast<double>(r.size());
    const VectorXd component = band_component(r, low, high);
    const double band_energy = component.squaredNorm() - n * band_noise;
    const bool motion = motion_at(samples, t, c.value);
    if (line_energy >= kLineShare * band_energy) {
      // A sinusoid fitted to noise captures one bin's worth on average.
      c.kind = motion ? "motion_periodic" : "time_periodic";
      c.energy = line_energy, c.noise = n * level[p.bin(c.value)], c.torque = line;
    } else {
      c.kind = motion ? "motion_periodic" : "band";
      c.energy = std::max(0.0, band_energy), c.noise = n * band_noise, c.torque = component;
    }
    // The side whose own signal carries the band's residual: with r = measured - model and the
    // structure s in one side only, <r, measured> = |s|^2 and <r, -model> = 0 if it is in the measured
    // torque, and the other way round if it is in the model's (the rest of each side, the motion's
    // torque, is independent of s). A structure locked to the motion is the robot's torque: it
    // correlates with the motion's torque on both sides, and the noise the model's inputs carry in
    // is not locked to the motion.
    const double in_measured = component.dot(band_component(measured, low, high)),
                 in_model = -component.dot(band_component(model, low, high));
    c.side = !motion && in_model > in_measured ? kModelInput : kMeasuredTorque;
    found.push_back(c);
    k = high;
  }
  return found;
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
    what = format("periodic in time at %.2f Hz (%.2f-%.2f Hz), a frequency the motion has: a torque that follows the "
                  "motion, not a vibration", u.value, u.band_low, u.band_high);
  if (u.kind == "band")
    what = format("power spread over %.2f-%.2f Hz, peak at %.2f Hz (an amplitude or frequency that varies: with the "
                  "configuration?)", u.band_low, u.band_high, u.value);
  if (u.kind == "position_periodic") what = format("periodic in q%d with period %.3f rad", j, u.value);
  if (u.kind == "velocity_sign") what = format("a step with the sign of dq%d (%.3f N m)", j, u.value);
  if (u.kind == "velocity") what = format("proportional to dq%d (%.3f N m s/rad)", j, u.value);
  if (u.kind == "hysteresis")
    what = format("a loop against dq%d: %.3f N m between accelerating and decelerating", j, u.value);
  if (u.kind == "acceleration") what = format("proportional to ddq%d (%.4f kg m^2)", j, u.value);
  if (u.kind == "torque_level") what = format("proportional to the model torque (%.1f %%)", 100.0 * u.value);
  if (u.kind == "torque_of_joint")
    what = format("proportional to joint %d's torque (%.2f %%): driven by joint %d (crosstalk of the torque sensors, "
                  "a coupling)", u.from_joint, 100.0 * u.value, u.from_joint);
  if (u.kind == "velocity_of_joint")
    what = format("proportional to dq%d (%.3f N m s/rad): driven by joint %d", u.from_joint, u.value, u.from_joint);
  if (u.kind == "position_of_joint")
    what = format("proportional to q%d (%.3f N m/rad): driven by joint %d", u.from_joint, u.value, u.from_joint);
  const std::string side = u.side == kModelInput
                               ? "in the model's torque, not the measured one: from its inputs (q, dq and ddq "
                                 "estimated from the log) or its fitted causes, not the robot"
                               : "in the measured torque";
  std::string mode;
  for (std::size_t m = 0; m < u.mode_joints.size(); ++m)
    mode += u.mode_joints[m] == u.joint
                ? format("%s%d", m == 0 ? "; coherent in its band on joints " : ", ", u.mode_joints[m])
                : format("%s%d (%.0f deg, coherence %.2f)", m == 0 ? "; coherent in its band on joints " : ", ",
                         u.mode_joints[m], u.mode_phase_deg[m], u.mode_coherence[m]);
  if (!mode.empty()) what += mode + ": one mode";
  const std::string effect = library_effect_of(u.kind);
  std::string tail = "no library effect";
  if (!effect.empty())
    tail = std::find(causes.begin(), causes.end(), effect) != causes.end()
               ? "left after " + effect + " was fitted"
               : "like " + effect + ", which was not significant over the whole arm";
  return format("joint %d: %.3f N m, %.1f times the noise there (%.0f %% of what is left), %s, %s; %s", j, u.size,
                u.floor_multiple, 100.0 * u.share, what.c_str(), side.c_str(), tail.c_str());
}

// The expected bins of a periodogram of `segment` samples (`frequencies` its bins) of white noise of
// unit variance on the grid, smoothed (derivative 0) or differentiated (1) by the samples' filter
// and kept as the samples are.
std::vector<double> filtered_noise_bins(const Samples& s, int derivative, const Periodogram& p, Eigen::Index segment,
                                        double sample_period) {
  std::vector<double> bins(p.power.size());
  for (std::size_t k = 0; k < bins.size(); ++k) {
    const double one_sided = k == 0 || static_cast<Eigen::Index>(2 * k) == segment ? 1.0 : 2.0;
    bins[k] = one_sided * s.filter->noise_spectrum(derivative, s.stride, p.frequency(k) * sample_period) /
              static_cast<double>(segment);
  }
  return bins;
}

// The noise floor of one joint's residual, bin by bin of its periodogram `p` (n samples): the
// sensor's noise through the smoothing filter, scaled to the measured torque's spectrum above
// kFloorAbove, plus the model input's (the velocity's noise through the differentiator and the mass
// matrix, or the logged acceleration's through the filter), scaled to the model torque's; both
// scales from Welch's average over quarter-length segments (the mass matrix changes along the log).
// White before the filter, each is exact for the generated logs; a coloured noise (the real log's)
// is fitted where it is measured and extrapolated with the filter's shape below.
struct Floor {
  std::vector<double> level;  // the residual's, per bin of p
  NoiseFloor rms;
};
Floor noise_floor(const Samples& s, const Periodogram& p, const VectorXd& measured, const VectorXd& model,
                  double sample_period, double mean_square) {
  const auto n = static_cast<Eigen::Index>(s.size()), segment = n / 4;
  auto scale = [&](const VectorXd& series, int derivative) {
    const Periodogram averaged = welch(series, sample_period, segment);
    return noise_scale(averaged, filtered_noise_bins(s, derivative, averaged, segment, sample_period), kFloorAbove);
  };
  const int input_derivative = s.ddq_differentiated ? 1 : 0;
  const double sensor = scale(measured, 0), from_input = scale(model, input_derivative);
  const std::vector<double> smoothed = filtered_noise_bins(s, 0, p, n, sample_period),
                            input = filtered_noise_bins(s, input_derivative, p, n, sample_period);
  Floor floor;
  double measured_power = 0.0, model_power = 0.0;
  for (std::size_t k = 0; k < smoothed.size(); ++k) {
    floor.level.push_back(sensor * smoothed[k] + from_input * input[k]);
    measured_power += sensor * smoothed[k], model_power += from_input * input[k];
  }
  // Never more than the residual has.
  const double cap = std::min(1.0, mean_square / std::max(measured_power + model_power, 1e-300));
  for (double& level : floor.level) level *= cap;
  floor.rms = {std::sqrt(cap * (measured_power + model_power)), std::sqrt(cap * measured_power),
               std::sqrt(cap * model_power)};
  return floor;
}

// A band standing on several joints at once is one mode of the arm (or of the model's inputs) seen on
// each. Each spectral structure's residual is compared with every other joint's in its band by their
// coherence (Welch, kModeSegments stretches): the joints whose coherence noise would exceed with
// probability kModeFalseAlarm at most share the mode, also where it stays below their own floor's
// detection; each with its phase relative to the structure's joint and its coherence. A structure
// that follows the motion is left alone: every joint moves at the motion's frequencies.
constexpr int kModeSegments = 8;
constexpr double kModeFalseAlarm = 1e-3;
void shared_modes(std::vector<UnexplainedStructure>& structures, const std::array<VectorXd, kNumJoints>& residuals,
                  double sample_period) {
  for (UnexplainedStructure& u : structures) {
    if (u.band_high <= 0.0 || u.kind == "motion_periodic") continue;
    const VectorXd& own = residuals[static_cast<std::size_t>(u.joint - 1)];
    std::vector<int> joints;
    std::vector<double> phases, coherences;
    for (int joint = 1; joint <= kNumJoints; ++joint) {
      const Coherence c = band_coherence(own, residuals[static_cast<std::size_t>(joint - 1)], sample_period,
                                         u.band_low, u.band_high, kModeSegments);
      if (joint != u.joint && c.magnitude_squared <= coherence_threshold(c.independent, kModeFalseAlarm)) continue;
      joints.push_back(joint);
      phases.push_back(joint == u.joint ? 0.0 : c.phase * 180.0 / M_PI);
      coherences.push_back(joint == u.joint ? 1.0 : c.magnitude_squared);
    }
    if (joints.size() < 2) continue;
    u.mode_joints = joints, u.mode_phase_deg = phases, u.mode_coherence = coherences;
  }
}

}  // namespace

Localisation localise_unexplained(const Part& part, const VectorXd& left, const std::vector<std::string>& causes) {
  Localisation out;
  const Samples& s = part.samples;
  const auto n = static_cast<Eigen::Index>(s.size());
  if (n < 64) return out;
  const double sample_period = (s.t.back() - s.t.front()) / static_cast<double>(n - 1);
  VectorXd t(n);
  for (Eigen::Index k = 0; k < n; ++k) t[k] = s.t[static_cast<std::size_t>(k)];
  std::array<VectorXd, kNumJoints> residuals;
  for (int j = 0; j < kNumJoints; ++j) {
    VectorXd r(n), q(n), measured(n), model(n);
    // Its own: offset, time_drift, velocity_sign, velocity, hysteresis (+1 speeding up, -1 slowing
    // down, signed with the motion: the loop's branch), acceleration, torque_level; then each other
    // joint's torque (the model's), velocity and position.
    std::vector<Column> names = {{"offset", 0},   {"time_drift", 0},   {"velocity_sign", 0}, {"velocity", 0},
                                 {"hysteresis", 0}, {"acceleration", 0}, {"torque_level", 0}};
    for (int other = 0; other < kNumJoints; ++other)
      if (other != j)
        for (const char* kind : {"torque_of_joint", "velocity_of_joint", "position_of_joint"})
          names.push_back({kind, other + 1});
    MatrixXd columns(n, static_cast<Eigen::Index>(names.size()));
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(k);
      const double dq = s.dq[i][j], ddq = s.ddq[i][j], sign = smooth_sign(dq);
      r[k] = left[kNumJoints * k + j], q[k] = s.q[i][j];
      measured[k] = s.tau[i][j], model[k] = s.tau[i][j] - r[k];  // the model with the causes
      columns.row(k).head<7>() << 1.0, t[k] - s.t.front(), sign, dq, std::tanh(ddq * dq / 0.01) * sign, ddq,
          part.predicted[i][j];
      Eigen::Index c = 7;
      for (int other = 0; other < kNumJoints; ++other)
        if (other != j) {
          columns(k, c++) = part.predicted[i][other];
          columns(k, c++) = s.dq[i][other];
          columns(k, c++) = s.q[i][other];
        }
    }
    // The drift and the other joints' columns centred: a constant is the offset's.
    columns.col(1).array() -= columns.col(1).mean();
    for (Eigen::Index c = 7; c < columns.cols(); ++c) columns.col(c).array() -= columns.col(c).mean();
    const double mean_square = r.squaredNorm() / static_cast<double>(n);
    residuals[static_cast<std::size_t>(j)] = r;

    const Floor floor_bins =
        noise_floor(s, periodogram(r, sample_period), measured, model, sample_period, mean_square);
    const std::vector<double>& level = floor_bins.level;
    const NoiseFloor& floor = floor_bins.rms;
    out.floor[static_cast<std::size_t>(j)] = floor;

    // What each fitted kind finds in noise alone.
    const FittedKinds kinds(columns, std::move(names), q);
    std::vector<double> threshold(static_cast<std::size_t>(kinds.count()), 0.0),
        in_noise(static_cast<std::size_t>(kinds.count()), 0.0);  // the mean capture
    std::mt19937_64 engine(1000u + static_cast<unsigned>(j));
    for (int draw = 0; draw < kSurrogates; ++draw) {
      const VectorXd noise = noise_like(level, n, engine);
      for (int kind = 0; kind < kinds.count(); ++kind) {
        const double captured = kinds.capture(kind, noise);
        const auto i = static_cast<std::size_t>(kind);
        threshold[i] = std::max(threshold[i], kNoiseMargin * captured);
        in_noise[i] += captured / kSurrogates;
      }
    }

    // The strongest structure above the floor, then the next on what it left.
    VectorXd rest = r;
    for (int found = 0; found < kMaxStructures; ++found) {
      std::vector<Candidate> candidates =
          bands(rest, t, sample_period, level, measured, model, s);
      for (int kind = 0; kind < kinds.count(); ++kind) {
        Candidate c;
        c.kind = kinds.name(kind).kind, c.from_joint = kinds.name(kind).from_joint;
        c.energy = kinds.capture(kind, rest, &c.value, &c.torque);
        c.noise = in_noise[static_cast<std::size_t>(kind)];
        if (c.energy > threshold[static_cast<std::size_t>(kind)]) candidates.push_back(c);
      }
      if (candidates.empty()) break;
      const Candidate& best = *std::max_element(candidates.begin(), candidates.end(),
                                                [](const auto& a, const auto& b) { return a.energy < b.energy; });
      const double size = std::sqrt(best.energy / static_cast<double>(n)), share = best.energy / r.squaredNorm();
      if (size < kUnexplainedSize || share < kUnexplainedShare) break;
      double value = best.value;
      if (best.kind == "time_drift") value *= 60.0;                                  // per minute
      if (best.kind == "velocity_sign" || best.kind == "hysteresis") value *= 2.0;  // the step between branches
      UnexplainedStructure u;
      u.joint = j + 1, u.kind = best.kind, u.size = size, u.share = share, u.value = value;
      u.floor_multiple = std::sqrt(best.energy / std::max(best.noise, 1e-300));
      u.band_low = best.band_low, u.band_high = best.band_high, u.side = best.side, u.from_joint = best.from_joint;
      out.structures.push_back(u);
      rest -= best.torque;
    }
  }
  shared_modes(out.structures, residuals, sample_period);
  for (UnexplainedStructure& u : out.structures) u.detail = describe(u, causes);
  std::sort(out.structures.begin(), out.structures.end(), [](const auto& a, const auto& b) { return a.size > b.size; });
  return out;
}

}  // namespace csp::gap
