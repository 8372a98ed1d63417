// The spectrum of a residual and its noise floor (docs/gap.md, "Noise floor, bands and sides").
// A residual is the sensor's noise, the noise the model's inputs carry into the prediction (ddq is
// differentiated from a noisy dq), and structure; structure is what stands above the floor.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

namespace csp::gap {

// The one-sided periodogram of a series with its mean removed, Hann-windowed (its side lobes fall
// as 1/k^3, so a strong line does not raise the bins around it far), zero-padded `padding` times
// (resolution 1 / (padding T) for a series of duration T). Normalised so that the bins of the
// unpadded periodogram sum to the series' mean square on average (Parseval with the window's power).
struct Periodogram {
  double bin_width = 0.0;      // [Hz]
  std::vector<double> power;   // per bin [unit^2], bins 0 .. n_fft / 2
  double frequency(std::size_t k) const { return bin_width * static_cast<double>(k); }
  // The bin nearest to `hz`, within the bins.
  std::size_t bin(double hz) const;
  // Sum of the bins from `low` to `high` [Hz].
  double band_power(double low, double high) const;
};
Periodogram periodogram(const Eigen::VectorXd& series, double sample_period, int padding = 1);

// Welch's average of the periodograms of `segment`-sample stretches overlapping by half (Hann
// windows overlapping by half sum to a constant): the power of a series whose level changes along
// it (noise through a mass matrix that changes with the configuration) averaged evenly over the
// series, which one window over the whole series, weighting its middle, does not.
Periodogram welch(const Eigen::VectorXd& series, double sample_period, Eigen::Index segment);

// The part of a series in its DFT bins low..high (and their negative-frequency twins): a band-pass
// with a sharp edge, zero phase.
Eigen::VectorXd band_component(const Eigen::VectorXd& series, std::size_t low, std::size_t high);

// The coherence of two series in the band [low, high] Hz: their cross-spectrum by Welch's method
// over `segments` non-overlapping Hann-windowed stretches, summed over the band's bins (at least the
// one nearest to it): |S_ab|^2 / (S_aa S_bb) in [0, 1], and b's phase relative to a's [rad].
// `independent` counts the (stretch, bin) pairs that are independent for noise (every other bin: a
// Hann window's bins share half their power with their neighbours).
struct Coherence {
  double magnitude_squared = 0.0;
  double phase = 0.0;
  int independent = 0;
};
Coherence band_coherence(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double sample_period, double low,
                         double high, int segments);

// What the magnitude-squared coherence of two independent Gaussian noises exceeds with probability
// `false_alarm`, estimated from `independent` pairs: 1 - false_alarm^(1 / (independent - 1)) (its
// distribution is Beta(1, independent - 1); Carter 1987). 1 when independent < 2: nothing is shown.
double coherence_threshold(int independent, double false_alarm);

// The scale c of a noise floor c shape[k] (shape: the expected bins of a unit noise), measured at
// `above` [Hz] and beyond, where the motion has no power (the excitation ends at about 2 Hz): the
// median of power / shape over those bins, divided by ln 2 (a bin of Gaussian noise is exponentially
// distributed, its median ln 2 times its mean; a line or a few strong bins move a median little).
double noise_scale(const Periodogram& p, const std::vector<double>& shape, double above);

// A Gaussian series of n samples whose unpadded periodogram has the expected bins `level`
// (level.size() = n / 2 + 1: a noise surrogate, to see what the fits find in noise alone).
Eigen::VectorXd noise_like(const std::vector<double>& level, Eigen::Index n, std::mt19937_64& engine);

}  // namespace csp::gap
