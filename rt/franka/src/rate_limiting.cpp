// limitRate of both libfranka API versions (franka/rate_limiting.h): 0.15's in namespace franka,
// 0.9's in franka::api_0_9; both on the same per-joint and per-vector laws below.
#include "franka/rate_limiting.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "franka/control_tools.h"

namespace franka {
namespace {

template <std::size_t N>
void require_finite(const std::array<double, N>& values, const char* what) {
  for (double v : values)
    if (!std::isfinite(v)) throw std::invalid_argument(std::string(what) + " is infinite or NaN.");
}

// One joint velocity in [lower, upper] with bounded acceleration and jerk: the jerk first; then the
// acceleration, bounded so that the jerk limit can still bring it to zero before the velocity
// reaches its bound (from acceleration a, the velocity still grows by a^2 / (2 j_max)).
double limit_velocity(double upper_velocity, double lower_velocity, double max_acceleration, double max_jerk,
                      double commanded_velocity, double last_velocity, double last_acceleration) {
  if (!std::isfinite(commanded_velocity)) throw std::invalid_argument("commanded_velocity is infinite or NaN.");
  const double jerk = std::clamp(((commanded_velocity - last_velocity) / kDeltaT - last_acceleration) / kDeltaT,
                                 -max_jerk, max_jerk);
  const double room_up = std::max(0.0, upper_velocity - last_velocity);
  const double room_down = std::max(0.0, last_velocity - lower_velocity);
  const double max_up = std::min(max_acceleration, std::sqrt(2.0 * max_jerk * room_up));
  const double max_down = std::min(max_acceleration, std::sqrt(2.0 * max_jerk * room_down));
  const double acceleration = std::clamp(last_acceleration + jerk * kDeltaT, -max_down, max_up);
  return std::clamp(last_velocity + acceleration * kDeltaT, lower_velocity, upper_velocity);
}

// One joint position: its implied velocity limited as above, integrated once.
double limit_position(double upper_velocity, double lower_velocity, double max_acceleration, double max_jerk,
                      double commanded_position, double last_position, double last_velocity, double last_acceleration) {
  if (!std::isfinite(commanded_position)) throw std::invalid_argument("commanded_position is infinite or NaN.");
  return last_position + limit_velocity(upper_velocity, lower_velocity, max_acceleration, max_jerk,
                                        (commanded_position - last_position) / kDeltaT, last_velocity,
                                        last_acceleration) *
                             kDeltaT;
}

using Array7 = std::array<double, 7>;

Array7 limit_velocities(const Array7& upper, const Array7& lower, const Array7& acceleration, const Array7& jerk,
                        const Array7& commanded, const Array7& last, const Array7& last_acceleration) {
  require_finite(commanded, "commanded_velocities");
  Array7 limited{};
  for (std::size_t i = 0; i < 7; ++i)
    limited[i] = limit_velocity(upper[i], lower[i], acceleration[i], jerk[i], commanded[i], last[i], last_acceleration[i]);
  return limited;
}

Array7 limit_positions(const Array7& upper, const Array7& lower, const Array7& acceleration, const Array7& jerk,
                       const Array7& commanded, const Array7& last, const Array7& last_velocity,
                       const Array7& last_acceleration) {
  require_finite(commanded, "commanded_positions");
  Array7 limited{};
  for (std::size_t i = 0; i < 7; ++i)
    limited[i] = limit_position(upper[i], lower[i], acceleration[i], jerk[i], commanded[i], last[i], last_velocity[i],
                                last_acceleration[i]);
  return limited;
}

Array7 negated(const Array7& values) {
  Array7 out{};
  for (std::size_t i = 0; i < 7; ++i) out[i] = -values[i];
  return out;
}

// A 3-vector velocity (translational or rotational part of a twist) limited in the norms of its
// jerk, acceleration and velocity, the same law as one joint along the direction of change.
Eigen::Vector3d limit_vector(double max_velocity, double max_acceleration, double max_jerk,
                             const Eigen::Vector3d& commanded, const Eigen::Vector3d& last,
                             const Eigen::Vector3d& last_acceleration) {
  Eigen::Vector3d jerk = ((commanded - last) / kDeltaT - last_acceleration) / kDeltaT;
  if (jerk.norm() > max_jerk) jerk *= max_jerk / jerk.norm();
  Eigen::Vector3d acceleration = last_acceleration + jerk * kDeltaT;
  // Room to the velocity bound along the acceleration's direction: |last + s u| = max_velocity.
  if (acceleration.norm() > kNormEps) {
    const Eigen::Vector3d u = acceleration.normalized();
    const double along = u.dot(last);
    const double room = std::max(0.0, -along + std::sqrt(std::max(0.0, along * along - last.squaredNorm() +
                                                                         max_velocity * max_velocity)));
    const double bound = std::min(max_acceleration, std::sqrt(2.0 * max_jerk * room));
    if (acceleration.norm() > bound) acceleration = u * bound;
  }
  Eigen::Vector3d velocity = last + acceleration * kDeltaT;
  if (velocity.norm() > max_velocity) velocity *= max_velocity / velocity.norm();
  return velocity;
}

}  // namespace

// ---- both versions

Array7 limitRate(const Array7& max_derivatives, const Array7& commanded_values, const Array7& last_commanded_values) {
  require_finite(commanded_values, "commanded_values");
  Array7 limited{};
  for (std::size_t i = 0; i < 7; ++i) {
    const double step = max_derivatives[i] * kDeltaT;
    limited[i] = last_commanded_values[i] + std::clamp(commanded_values[i] - last_commanded_values[i], -step, step);
  }
  return limited;
}

std::array<double, 6> limitRate(double max_translational_velocity, double max_translational_acceleration,
                                double max_translational_jerk, double max_rotational_velocity,
                                double max_rotational_acceleration, double max_rotational_jerk,
                                const std::array<double, 6>& O_dP_EE_c, const std::array<double, 6>& last_O_dP_EE_c,
                                const std::array<double, 6>& last_O_ddP_EE_c) {
  require_finite(O_dP_EE_c, "O_dP_EE_c");
  using Vector6 = Eigen::Matrix<double, 6, 1>;
  const Vector6 twist = Vector6::Map(O_dP_EE_c.data()), last = Vector6::Map(last_O_dP_EE_c.data()),
                last_acceleration = Vector6::Map(last_O_ddP_EE_c.data());
  Vector6 limited;
  limited.head<3>() = limit_vector(max_translational_velocity, max_translational_acceleration, max_translational_jerk,
                                   twist.head<3>(), last.head<3>(), last_acceleration.head<3>());
  limited.tail<3>() = limit_vector(max_rotational_velocity, max_rotational_acceleration, max_rotational_jerk,
                                   twist.tail<3>(), last.tail<3>(), last_acceleration.tail<3>());
  std::array<double, 6> out{};
  Vector6::Map(out.data()) = limited;
  return out;
}

std::array<double, 16> limitRate(double max_translational_velocity, double max_translational_acceleration,
                                 double max_translational_jerk, double max_rotational_velocity,
                                 double max_rotational_acceleration, double max_rotational_jerk,
                                 const std::array<double, 16>& O_T_EE_c, const std::array<double, 16>& last_O_T_EE_c,
                                 const std::array<double, 6>& last_O_dP_EE_c,
                                 const std::array<double, 6>& last_O_ddP_EE_c) {
  require_finite(O_T_EE_c, "O_T_EE_c");
  if (!isHomogeneousTransformation(O_T_EE_c))
    throw std::invalid_argument("O_T_EE_c is invalid transformation matrix. Has to be column major!");
  const Eigen::Matrix4d pose = Eigen::Matrix4d::Map(O_T_EE_c.data());
  const Eigen::Matrix4d last = Eigen::Matrix4d::Map(last_O_T_EE_c.data());
  // The twist from the last pose to this one: translation difference, rotation vector of R R_last^T.
  const Eigen::AngleAxisd rotation(Eigen::Matrix3d(pose.topLeftCorner<3, 3>() * last.topLeftCorner<3, 3>().transpose()));
  std::array<double, 6> twist{};
  Eigen::Vector3d::Map(twist.data()) = (pose.topRightCorner<3, 1>() - last.topRightCorner<3, 1>()) / kDeltaT;
  Eigen::Vector3d::Map(twist.data() + 3) = rotation.axis() * rotation.angle() / kDeltaT;
  const std::array<double, 6> limited =
      limitRate(max_translational_velocity, max_translational_acceleration, max_translational_jerk,
                kFactorCartesianRotationPoseInterface * max_rotational_velocity,
                kFactorCartesianRotationPoseInterface * max_rotational_acceleration,
                kFactorCartesianRotationPoseInterface * max_rotational_jerk, twist, last_O_dP_EE_c, last_O_ddP_EE_c);
  // Integrated once from the last pose.
  const Eigen::Vector3d w = Eigen::Vector3d::Map(limited.data() + 3);
  Eigen::Matrix4d out_pose = Eigen::Matrix4d::Identity();
  out_pose.topRightCorner<3, 1>() = last.topRightCorner<3, 1>() + Eigen::Vector3d::Map(limited.data()) * kDeltaT;
  const Eigen::Matrix3d step = w.norm() > kNormEps ? Eigen::AngleAxisd(w.norm() * kDeltaT, w.normalized()).toRotationMatrix()
                                                   : Eigen::Matrix3d::Identity();
  out_pose.topLeftCorner<3, 3>() = step * last.topLeftCorner<3, 3>();
  std::array<double, 16> out{};
  Eigen::Matrix4d::Map(out.data()) = out_pose;
  return out;
}

// ---- libfranka 0.15

double limitRate(double upper_limits_velocity, double lower_limits_velocity, double max_acceleration, double max_jerk,
                 double commanded_velocity, double last_commanded_velocity, double last_commanded_acceleration) {
  return limit_velocity(upper_limits_velocity, lower_limits_velocity, max_acceleration, max_jerk, commanded_velocity,
                        last_commanded_velocity, last_commanded_acceleration);
}

double limitRate(double upper_limits_velocity, double lower_limits_velocity, double max_acceleration, double max_jerk,
                 double commanded_position, double last_commanded_position, double last_commanded_velocity,
                 double last_commanded_acceleration) {
  return limit_position(upper_limits_velocity, lower_limits_velocity, max_acceleration, max_jerk, commanded_position,
                        last_commanded_position, last_commanded_velocity, last_commanded_acceleration);
}

Array7 limitRate(const Array7& upper_limits_velocity, const Array7& lower_limits_velocity,
                 const Array7& max_acceleration, const Array7& max_jerk, const Array7& commanded_velocities,
                 const Array7& last_commanded_velocities, const Array7& last_commanded_accelerations) {
  return limit_velocities(upper_limits_velocity, lower_limits_velocity, max_acceleration, max_jerk,
                          commanded_velocities, last_commanded_velocities, last_commanded_accelerations);
}

Array7 limitRate(const Array7& upper_limits_velocity, const Array7& lower_limits_velocity,
                 const Array7& max_acceleration, const Array7& max_jerk, const Array7& commanded_positions,
                 const Array7& last_commanded_positions, const Array7& last_commanded_velocities,
                 const Array7& last_commanded_accelerations) {
  return limit_positions(upper_limits_velocity, lower_limits_velocity, max_acceleration, max_jerk,
                         commanded_positions, last_commanded_positions, last_commanded_velocities,
                         last_commanded_accelerations);
}

// ---- libfranka 0.9: symmetric velocity limits

inline namespace api_0_9 {

double limitRate(double max_velocity, double max_acceleration, double max_jerk, double commanded_velocity,
                 double last_commanded_velocity, double last_commanded_acceleration) {
  return limit_velocity(max_velocity, -max_velocity, max_acceleration, max_jerk, commanded_velocity,
                        last_commanded_velocity, last_commanded_acceleration);
}

double limitRate(double max_velocity, double max_acceleration, double max_jerk, double commanded_position,
                 double last_commanded_position, double last_commanded_velocity, double last_commanded_acceleration) {
  return limit_position(max_velocity, -max_velocity, max_acceleration, max_jerk, commanded_position,
                        last_commanded_position, last_commanded_velocity, last_commanded_acceleration);
}

Array7 limitRate(const Array7& max_velocity, const Array7& max_acceleration, const Array7& max_jerk,
                 const Array7& commanded_velocities, const Array7& last_commanded_velocities,
                 const Array7& last_commanded_accelerations) {
  return limit_velocities(max_velocity, negated(max_velocity), max_acceleration, max_jerk, commanded_velocities,
                          last_commanded_velocities, last_commanded_accelerations);
}

Array7 limitRate(const Array7& max_velocity, const Array7& max_acceleration, const Array7& max_jerk,
                 const Array7& commanded_positions, const Array7& last_commanded_positions,
                 const Array7& last_commanded_velocities, const Array7& last_commanded_accelerations) {
  return limit_positions(max_velocity, negated(max_velocity), max_acceleration, max_jerk, commanded_positions,
                         last_commanded_positions, last_commanded_velocities, last_commanded_accelerations);
}

}  // namespace api_0_9

}  // namespace franka
