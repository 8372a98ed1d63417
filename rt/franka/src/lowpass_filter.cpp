#include "franka/lowpass_filter.h"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace franka {
namespace {

// The filter's gain a = T / (T + 1 / (2 pi f_c)), after checking its inputs.
double filter_gain(double sample_time, double cutoff_frequency) {
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    throw std::invalid_argument("lowpassFilter: sample_time must be positive and finite");
  if (!(cutoff_frequency > 0.0) || !std::isfinite(cutoff_frequency))
    throw std::invalid_argument("lowpassFilter: cutoff_frequency must be positive and finite");
  const double time_constant = 1.0 / (2.0 * M_PI * cutoff_frequency);
  return sample_time / (sample_time + time_constant);
}

}  // namespace

double lowpassFilter(double sample_time, double y, double y_last, double cutoff_frequency) {
  const double gain = filter_gain(sample_time, cutoff_frequency);
  if (!std::isfinite(y) || !std::isfinite(y_last))
    throw std::invalid_argument("lowpassFilter: the values to filter must be finite");
  return y_last + gain * (y - y_last);
}

std::array<double, 16> cartesianLowpassFilter(double sample_time, std::array<double, 16> y,
                                              std::array<double, 16> y_last, double cutoff_frequency) {
  const double gain = filter_gain(sample_time, cutoff_frequency);
  for (std::size_t i = 0; i < 16; ++i)
    if (!std::isfinite(y[i]) || !std::isfinite(y_last[i]))
      throw std::invalid_argument("cartesianLowpassFilter: the poses to filter must be finite");
  const Eigen::Matrix4d pose = Eigen::Matrix4d::Map(y.data());
  const Eigen::Matrix4d last = Eigen::Matrix4d::Map(y_last.data());
  const Eigen::Quaterniond rotation(Eigen::Matrix3d(pose.topLeftCorner<3, 3>()));
  const Eigen::Quaterniond last_rotation(Eigen::Matrix3d(last.topLeftCorner<3, 3>()));
  Eigen::Matrix4d filtered = Eigen::Matrix4d::Identity();
  filtered.topRightCorner<3, 1>() =
      last.topRightCorner<3, 1>() + gain * (pose.topRightCorner<3, 1>() - last.topRightCorner<3, 1>());
  filtered.topLeftCorner<3, 3>() = last_rotation.slerp(gain, rotation).normalized().toRotationMatrix();
  std::array<double, 16> out{};
  Eigen::Matrix4d::Map(out.data()) = filtered;
  return out;
}

}  // namespace franka
