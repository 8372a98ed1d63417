#include "franka/lowpass_filter.h"

#include <cmath>
#include <stdexcept>

namespace franka {

double lowpassFilter(double sample_time, double y, double y_last, double cutoff_frequency) {
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    throw std::invalid_argument("lowpassFilter: sample_time must be positive and finite");
  if (!(cutoff_frequency > 0.0) || !std::isfinite(cutoff_frequency))
    throw std::invalid_argument("lowpassFilter: cutoff_frequency must be positive and finite");
  if (!std::isfinite(y) || !std::isfinite(y_last))
    throw std::invalid_argument("lowpassFilter: the values to filter must be finite");
  const double time_constant = 1.0 / (2.0 * M_PI * cutoff_frequency);
  const double gain = sample_time / (sample_time + time_constant);
  return y_last + gain * (y - y_last);
}

}  // namespace franka
