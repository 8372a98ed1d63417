#include "csp/gap/spectrum.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>

namespace csp::gap {

std::size_t Periodogram::bin(double hz) const {
  const double k = std::round(hz / bin_width);
  return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(power.size() - 1)));
}

double Periodogram::band_power(double low, double high) const {
  double sum = 0.0;
  for (std::size_t k = bin(low); k <= bin(high); ++k) sum += power[k];
  return sum;
}

Periodogram periodogram(const Eigen::VectorXd& series, double sample_period, int padding) {
  const auto n = static_cast<std::size_t>(series.size());
  const std::size_t n_fft = static_cast<std::size_t>(padding) * n;
  const double mean = series.mean();
  std::vector<double> windowed(n_fft, 0.0);
  double window_power = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(i) / static_cast<double>(n - 1));
    windowed[i] = w * (series[static_cast<Eigen::Index>(i)] - mean);
    window_power += w * w;
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, windowed);
  Periodogram p;
  p.bin_width = 1.0 / (static_cast<double>(n_fft) * sample_period);
  p.power.resize(n_fft / 2 + 1);
  // One-sided: each bin inside the band counts its negative-frequency twin; 0 and n_fft / 2 have none.
  const double scale = 2.0 / (static_cast<double>(n_fft) * window_power);
  for (std::size_t k = 0; k < p.power.size(); ++k)
    p.power[k] = (k == 0 || 2 * k == n_fft ? 0.5 : 1.0) * scale * std::norm(spectrum[k]);
  return p;
}

Periodogram welch(const Eigen::VectorXd& series, double sample_period, Eigen::Index segment) {
  Periodogram average;
  int count = 0;
  for (Eigen::Index start = 0; start + segment <= series.size(); start += segment / 2, ++count) {
    const Periodogram p = periodogram(series.segment(start, segment), sample_period);
    if (average.power.empty()) average = p;
    else
      for (std::size_t k = 0; k < p.power.size(); ++k) average.power[k] += p.power[k];
  }
  for (double& bin : average.power) bin /= count;
  return average;
}

Coherence band_coherence(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double sample_period, double low,
                         double high, int segments) {
  const Eigen::Index length = std::min(a.size(), b.size()) / segments;
  Coherence c;
  if (length < 8) return c;
  const double bin_width = 1.0 / (static_cast<double>(length) * sample_period);
  const auto nearest = [&](double hz) { return static_cast<std::size_t>(std::max(0.0, std::round(hz / bin_width))); };
  const std::size_t first = std::max<std::size_t>(1, nearest(low)),
                    last = std::min(std::max(first, nearest(high)), static_cast<std::size_t>(length / 2));
  Eigen::FFT<double> fft;
  std::complex<double> ab = 0.0;
  double aa = 0.0, bb = 0.0;
  for (int s = 0; s < segments; ++s) {
    std::array<std::vector<std::complex<double>>, 2> spectra;
    for (int side = 0; side < 2; ++side) {
      const Eigen::VectorXd x = (side == 0 ? a : b).segment(s * length, length);
      const double mean = x.mean();
      std::vector<double> windowed(static_cast<std::size_t>(length));
      for (Eigen::Index i = 0; i < length; ++i)
        windowed[static_cast<std::size_t>(i)] =
            (0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(i) / static_cast<double>(length - 1))) * (x[i] - mean);
      fft.fwd(spectra[static_cast<std::size_t>(side)], windowed);
    }
    for (std::size_t k = first; k <= last; ++k) {
      ab += spectra[1][k] * std::conj(spectra[0][k]);
      aa += std::norm(spectra[0][k]), bb += std::norm(spectra[1][k]);
    }
  }
  c.magnitude_squared = aa > 0.0 && bb > 0.0 ? std::norm(ab) / (aa * bb) : 0.0;
  c.phase = std::arg(ab);
  c.independent = segments * static_cast<int>((last - first) / 2 + 1);
  return c;
}

double coherence_threshold(int independent, double false_alarm) {
  return independent < 2 ? 1.0 : 1.0 - std::pow(false_alarm, 1.0 / (independent - 1));
}

Eigen::VectorXd band_component(const Eigen::VectorXd& series, std::size_t low, std::size_t high) {
  Eigen::FFT<double> fft;
  std::vector<double> values(series.data(), series.data() + series.size());
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, values);
  const std::size_t n = values.size();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t folded = std::min(k, n - k);
    if (folded < low || folded > high) spectrum[k] = 0.0;
  }
  fft.inv(values, spectrum);
  return Eigen::Map<const Eigen::VectorXd>(values.data(), series.size());
}

double noise_scale(const Periodogram& p, const std::vector<double>& shape, double above) {
  const std::size_t last = p.power.size() - 1;  // the Nyquist bin, real: not exponential
  // Too close to the Nyquist frequency for a median (a coarse --sample-period): the upper half.
  std::size_t first = p.bin(above);
  if (first + 10 > last) first = last / 2;
  std::vector<double> ratios;
  for (std::size_t k = first; k < last; ++k)
    if (shape[k] > 0.0) ratios.push_back(p.power[k] / shape[k]);
  if (ratios.empty()) return 0.0;
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  return *middle / std::log(2.0);
}

Eigen::VectorXd noise_like(const std::vector<double>& level, Eigen::Index n, std::mt19937_64& engine) {
  // White Gaussian noise of variance s^2 has DFT bins of mean square n s^2 and (Hann) periodogram
  // bins 2 s^2 / n: a DFT bin of mean square n^2 level / 2 gives a periodogram bin of mean `level`.
  std::normal_distribution<double> gauss;
  const auto size = static_cast<std::size_t>(n);
  std::vector<std::complex<double>> spectrum(size, 0.0);
  for (std::size_t k = 0; 2 * k <= size; ++k) {
    const double amplitude = std::sqrt(static_cast<double>(n) * static_cast<double>(n) * level[k] / 4.0);
    // The mean (k = 0) and the Nyquist bin are real: all of their power in one Gaussian.
    const bool real = k == 0 || 2 * k == size;
    spectrum[k] = real ? std::complex<double>(std::sqrt(2.0) * amplitude * gauss(engine), 0.0)
                       : std::complex<double>(amplitude * gauss(engine), amplitude * gauss(engine));
    if (k > 0) spectrum[size - k] = std::conj(spectrum[k]);
  }
  Eigen::FFT<double> fft;
  std::vector<double> series;
  fft.inv(series, spectrum);
  return Eigen::Map<const Eigen::VectorXd>(series.data(), n);
}

}  // namespace csp::gap
