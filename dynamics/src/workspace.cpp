#include "csp/dynamics/workspace.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "csp/dynamics/algorithms.hpp"

namespace csp {
namespace {

void update(ReachStatistics& stats, const Vector3& p, const Vector3& shoulder, const Vector7& q) {
  const double reach = (p - shoulder).norm();
  if (reach > stats.max_reach) {
    stats.max_reach = reach;
    stats.q_at_max_reach = q;
  }
  stats.max_radius = std::max(stats.max_radius, std::hypot(p.x(), p.y()));
  stats.z_min = std::min(stats.z_min, p.z());
  stats.z_max = std::max(stats.z_max, p.z());
}

// Cell index of v on [min, min + n * width), or -1 outside (NaN included).
int cell_index(double v, double min, double width, int n) {
  const double i = std::floor((v - min) / width);
  return (i >= 0.0 && i < n) ? static_cast<int>(i) : -1;
}

}  // namespace

Histogram2D::Histogram2D(double x_min_, double x_max_, double y_min_, double y_max_, int nx_, int ny_)
    : x_min(x_min_), x_max(x_max_), y_min(y_min_), y_max(y_max_), nx(nx_), ny(ny_),
      counts(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), 0) {
  if (nx < 1 || ny < 1 || !(x_max > x_min) || !(y_max > y_min))
    throw std::invalid_argument("Histogram2D: need at least one cell and a non-empty range");
}

void Histogram2D::add(double x, double y) {
  const int ix = cell_index(x, x_min, cell_width(), nx);
  const int iy = cell_index(y, y_min, cell_height(), ny);
  if (ix < 0 || iy < 0)
    ++outside;
  else
    ++counts[static_cast<std::size_t>(iy) * nx + ix];
}

std::uint64_t Histogram2D::inside() const {
  std::uint64_t sum = 0;
  for (const std::uint64_t c : counts) sum += c;
  return sum;
}

double reach_upper_bound(const Model& model, Frame frame) {
  const ModelParameters& p = model.parameters();
  double bound = p.link7_T_flange.translation.norm();
  // Joints 1 and 2 only move the shoulder; every later row adds an offset a x + d z with x perpendicular to z.
  for (int i = 2; i < kNumJoints; ++i) bound += std::hypot(p.joints[i].a, p.joints[i].d);
  if (frame == Frame::kEndEffector) bound += p.F_T_EE.translation.norm();
  return bound;
}

Vector7 uniform_joint_sample(const JointLimits& limits, std::mt19937_64& engine) {
  Vector7 q;
  for (int i = 0; i < kNumJoints; ++i) {
    const double u = static_cast<double>(engine() >> 11) * 0x1.0p-53;
    q[i] = limits.q_min[i] + u * (limits.q_max[i] - limits.q_min[i]);
  }
  return q;
}

WorkspaceResult sample_workspace(const Model& model, const WorkspaceOptions& options,
                                 const WorkspaceCallback& on_point) {
  if (options.samples <= 0)
    throw std::invalid_argument("workspace: samples must be positive, got " + std::to_string(options.samples));
  if (options.grid < 1)
    throw std::invalid_argument("workspace: grid must have at least 1 cell per axis, got " + std::to_string(options.grid));
  if (options.frame != Frame::kFlange && options.frame != Frame::kEndEffector)
    throw std::invalid_argument("workspace: the histogram frame must be the flange or the end effector");
  const JointLimits& limits = model.parameters().joint_limits;
  if ((limits.q_min.array() > limits.q_max.array()).any())
    throw std::invalid_argument("workspace: joint limits with q_min > q_max");

  Data data;
  WorkspaceResult result;
  result.samples = options.samples;
  forward_kinematics(model, data, Vector7::Zero());
  result.shoulder = data.O_T_joint[1].translation;
  result.reach_bound = reach_upper_bound(model, options.frame);

  // Square grids centred on the base axis (top) and on the shoulder height (side), half-size the
  // reach bound rounded up to 0.1 m so that every sample lands inside and cells have round sizes.
  const double half = std::ceil((result.shoulder.head<2>().norm() + result.reach_bound) * 10.0) / 10.0;
  const double z0 = result.shoulder.z();
  result.side = Histogram2D(-half, half, z0 - half, z0 + half, options.grid, options.grid);
  result.top = Histogram2D(-half, half, -half, half, options.grid, options.grid);

  std::mt19937_64 engine(options.seed);
  for (std::int64_t n = 0; n < options.samples; ++n) {
    if (n % 65536 == 0) report(options.progress, "sampling", static_cast<double>(n), static_cast<double>(options.samples));
    const Vector7 q = uniform_joint_sample(limits, engine);
    forward_kinematics(model, data, q);
    const Vector3& shoulder = data.O_T_joint[1].translation;
    const Vector3& flange = data.O_T_F.translation;
    const Vector3& end_effector = data.O_T_EE.translation;
    update(result.flange, flange, shoulder, q);
    update(result.end_effector, end_effector, shoulder, q);

    const Vector3& p = options.frame == Frame::kFlange ? flange : end_effector;
    const double radius = std::hypot(p.x(), p.y());
    result.side.add(p.x() >= 0.0 ? radius : -radius, p.z());
    result.top.add(p.x(), p.y());
    if (on_point) on_point(WorkspacePoint{q, flange, end_effector, shoulder});
  }
  return result;
}

}  // namespace csp
