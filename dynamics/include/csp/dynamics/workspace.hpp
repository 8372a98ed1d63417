// Reachable workspace by Monte-Carlo sampling of the joint space (the seed paper's Fig. 3):
// uniform joint configurations within the joint limits, their flange and end-effector positions
// by forward kinematics, streaming reach statistics and two fixed-grid density histograms.
// Pure math: no I/O. Points are not stored; pass a callback to see each one.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "csp/dynamics/model.hpp"
#include "csp/dynamics/progress.hpp"

namespace csp {

// Counts on a fixed nx x ny grid of cells over [x_min, x_max) x [y_min, y_max).
struct Histogram2D {
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
  int nx = 0, ny = 0;
  std::vector<std::uint64_t> counts;   // counts[iy * nx + ix]; ix = 0 at x_min, iy = 0 at y_min
  std::uint64_t outside = 0;           // points that fell outside the grid

  Histogram2D() = default;
  Histogram2D(double x_min, double x_max, double y_min, double y_max, int nx, int ny);

  void add(double x, double y);
  std::uint64_t at(int ix, int iy) const { return counts[static_cast<std::size_t>(iy) * nx + ix]; }
  std::uint64_t inside() const;   // sum of all cell counts
  double cell_width() const { return (x_max - x_min) / nx; }
  double cell_height() const { return (y_max - y_min) / ny; }
};

struct WorkspaceOptions {
  std::int64_t samples = 1'000'000;
  std::uint64_t seed = 1;
  Frame frame = Frame::kEndEffector;   // whose positions fill the histograms: kFlange or kEndEffector
  int grid = 200;                      // cells per axis of each histogram (square cells)
  Progress progress;                   // "sampling", every 65 536 samples
};

// Extremes of one frame's sampled positions (base frame, metres).
struct ReachStatistics {
  double max_reach = 0.0;                  // max |p - shoulder|, shoulder = joint-2 origin
  Vector7 q_at_max_reach = Vector7::Zero();
  double max_radius = 0.0;                 // max sqrt(x^2 + y^2): distance from the joint-1 (base z) axis
  double z_min = std::numeric_limits<double>::infinity();
  double z_max = -std::numeric_limits<double>::infinity();
};

// One sample, as handed to the optional callback (valid only during the call).
struct WorkspacePoint {
  const Vector7& q;
  const Vector3& flange;         // O_T_F translation
  const Vector3& end_effector;   // O_T_EE translation (= flange when F_T_EE is the identity)
  const Vector3& shoulder;       // joint-2 origin, O_T_joint[1] translation
};

struct WorkspaceResult {
  std::int64_t samples = 0;
  ReachStatistics flange, end_effector;
  Vector3 shoulder = Vector3::Zero();   // joint-2 origin at q = 0 (fixed for the Panda: (0, 0, 0.333))
  double reach_bound = 0.0;             // reach_upper_bound(model, options.frame)
  // Side view: horizontal axis is the signed horizontal radius sign(x) * sqrt(x^2 + y^2), i.e. each
  // point swung about the base z axis into the x-z plane on its own side (x >= 0 front, x < 0 back),
  // vertical axis z. A section through the base like Franka's datasheet drawing; shows the true
  // envelope whatever the joint-1 angle.
  Histogram2D side;
  Histogram2D top;   // x-y plane (all z)
};

// Upper bound on |p - shoulder| for `frame` (kFlange or kEndEffector) by the triangle inequality:
// the sum of the MDH row offsets sqrt(a^2 + d^2) of joints 3..7, the flange offset and, for the
// end effector, |F_T_EE translation|. Sizes the histogram grids so that no sample falls outside.
double reach_upper_bound(const Model& model, Frame frame);

// The sampling distribution: q_i = q_min_i + u_i (q_max_i - q_min_i) for joints 1..7 in order,
// u_i = (top 53 bits of one engine draw) / 2^53, uniform on [0, 1). Written out rather than
// std::uniform_real_distribution (implementation-defined) so a seed gives the same samples on
// every standard library.
Vector7 uniform_joint_sample(const JointLimits& limits, std::mt19937_64& engine);

using WorkspaceCallback = std::function<void(const WorkspacePoint&)>;

// Draws options.samples configurations from std::mt19937_64(options.seed) with uniform_joint_sample
// over model.parameters().joint_limits. Throws std::invalid_argument for samples <= 0, grid < 1,
// a frame other than kFlange/kEndEffector, or q_min > q_max.
WorkspaceResult sample_workspace(const Model& model, const WorkspaceOptions& options,
                                 const WorkspaceCallback& on_point = {});

}  // namespace csp
