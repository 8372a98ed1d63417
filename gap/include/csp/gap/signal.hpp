// From a joint log to smooth samples: resample onto a uniform grid (linear interpolation), smooth
// and differentiate with a zero-phase Savitzky-Golay filter, then keep every k-th sample.
// The same filter is applied to the measured torque as to the motion, so the model prediction
// (a function of filtered q, dq, ddq) and the measurement see the same frequency response.
#pragma once

#include <Eigen/Core>
#include <memory>

#include "csp/io/joint_log.hpp"

namespace csp::gap {

struct FilterOptions {
  double window = 0.101;        // Savitzky-Golay window [s] (-3 dB at 10.5 Hz at order 3)
  int order = 3;                // polynomial order
  double sample_period = 0.01;  // period of the samples kept for fitting [s] (Nyquist 50 Hz)
};

// Least-squares polynomial of degree `order` through 2 m + 1 equally spaced points (spacing dt),
// evaluated at the centre: value and first derivative are fixed weighted sums of the points.
class SavitzkyGolay {
 public:
  SavitzkyGolay(int half_width, int order, double dt);
  int half_width() const { return half_width_; }
  // Weighted sum of series[centre - m .. centre + m]; derivative = 0 (value) or 1 (d/dt).
  Vector7 apply(const std::vector<Vector7>& series, std::size_t centre, int derivative) const;
  // The power spectral density of white noise of unit variance on the grid, smoothed (derivative 0)
  // or differentiated (1) by this filter and then kept every `stride`-th sample, at `frequency` in
  // cycles per kept sample (0 .. 0.5): sum over m of R(m) cos(2 pi frequency m), R(m) the
  // autocorrelation of the weights at lag m stride (aliasing included). Its mean over the band is
  // the kept samples' variance, R(0).
  double noise_spectrum(int derivative, std::size_t stride, double frequency) const;

 private:
  int half_width_;
  Eigen::VectorXd value_weights_, derivative_weights_;
};

// Filtered samples of one log (one part: training or held out).
struct Samples {
  std::string source;
  std::vector<double> t;
  std::vector<Vector7> q, dq, ddq;  // ddq: derivative of dq (or the log's smoothed ddq)
  std::vector<Vector7> tau;         // filtered measured torque
  std::vector<Vector7> dtau;        // its time derivative
  std::size_t size() const { return t.size(); }

  // The uniform grid before smoothing, for laws with features faster than the filter (a friction
  // change within a few hundredths of a rad/s): such a law must be evaluated on the grid and then
  // smoothed, as the measured torque was, not evaluated on the smoothed motion.
  std::vector<Vector7> grid_q, grid_dq;
  std::vector<std::size_t> grid_index;           // grid index of each sample
  std::size_t stride = 1;                        // grid points per sample
  bool ddq_differentiated = true;                // ddq is dq differentiated (else the log's ddq, smoothed)
  std::shared_ptr<const SavitzkyGolay> filter;   // the smoothing filter of the samples
  // A series on the grid smoothed at each sample's grid index, as the measured torque is.
  std::vector<Vector7> smoothed(const std::vector<Vector7>& grid_series) const;
};

// Checks that the log's time can be put on a uniform grid and returns its spacing, the median time
// step. Throws JointLogError naming the log for fewer than 2 rows, a step longer than the filter's
// window (a gap in the recording: the times where it is) and steps so uneven that the grid would
// hold more than 4 points per row.
double check_time_steps(const JointLog& log, const FilterOptions& options);

// Throws JointLogError when the log's time fails check_time_steps or the log is too short for the
// filter window.
Samples filter_log(const JointLog& log, const FilterOptions& options);

}  // namespace csp::gap
