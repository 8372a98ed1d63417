#include "csp/gap/part.hpp"

#include <algorithm>
#include <cmath>

#include "csp/dynamics/batch.hpp"

namespace csp::gap {

// All samples at once (dynamics/batch.hpp: the one-state rnea's and InertialRegressor's results to
// rounding).
Part evaluate_part(const Model& model, Samples samples) {
  Part part;
  const std::size_t n = samples.size();
  StateBatch states(static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k < n; ++k) {
    const auto column = static_cast<Eigen::Index>(k);
    states.q.col(column) = samples.q[k];
    states.dq.col(column) = samples.dq[k];
    states.ddq.col(column) = samples.ddq[k];
  }
  StateBatch at_rest = states;   // g(q) is the torque at rest
  at_rest.dq.setZero();
  at_rest.ddq.setZero();
  // Gravity is linear in the gravity vector: a small tilt by angle a about base axis e turns g
  // into g + a e x g, adding the gravity torque of the vector e x g.
  const Model tilt_x = with_gravity(model, Vector3::UnitX().cross(model.gravity()));
  const Model tilt_y = with_gravity(model, Vector3::UnitY().cross(model.gravity()));
  JointMatrix tau, g, gx, gy;
  rnea_batch(model, states, tau);
  rnea_batch(model, at_rest, g);
  rnea_batch(tilt_x, at_rest, gx);
  rnea_batch(tilt_y, at_rest, gy);
  inertial_regressor_batch(model, states, part.inertial);
  part.tilt.resize(part.inertial.rows(), 2);
  part.tilt.col(0) = gx.reshaped();   // column-major: row 7 k + j is joint j of sample k
  part.tilt.col(1) = gy.reshaped();
  for (std::size_t k = 0; k < n; ++k) {
    const auto column = static_cast<Eigen::Index>(k);
    part.predicted.push_back(tau.col(column) + friction_torque(model.parameters().friction, samples.dq[k]));
    part.gravity.push_back(g.col(column));
  }
  part.residual = stack(samples.tau) - stack(part.predicted);
  part.samples = std::move(samples);
  return part;
}

Part subset(const Part& part, const std::vector<bool>& keep) {
  Part out;
  const Samples& from = part.samples;
  Samples& to = out.samples;
  to.source = from.source, to.grid_q = from.grid_q, to.grid_dq = from.grid_dq, to.filter = from.filter;
  to.stride = from.stride, to.ddq_differentiated = from.ddq_differentiated;
  std::vector<Eigen::Index> rows;
  for (std::size_t k = 0; k < from.size(); ++k) {
    if (!keep[k]) continue;
    to.t.push_back(from.t[k]), to.q.push_back(from.q[k]), to.dq.push_back(from.dq[k]), to.ddq.push_back(from.ddq[k]);
    to.tau.push_back(from.tau[k]), to.dtau.push_back(from.dtau[k]), to.grid_index.push_back(from.grid_index[k]);
    out.predicted.push_back(part.predicted[k]), out.gravity.push_back(part.gravity[k]);
    for (int j = 0; j < kNumJoints; ++j) rows.push_back(kNumJoints * static_cast<Eigen::Index>(k) + j);
  }
  out.residual = part.residual(rows);
  out.inertial = part.inertial(rows, Eigen::all);
  out.tilt = part.tilt(rows, Eigen::all);
  return out;
}

Eigen::VectorXd stack(const std::vector<Vector7>& series) {
  Eigen::VectorXd out(kNumJoints * static_cast<Eigen::Index>(series.size()));
  for (std::size_t k = 0; k < series.size(); ++k)
    out.segment<kNumJoints>(kNumJoints * static_cast<Eigen::Index>(k)) = series[k];
  return out;
}

Stretches stretch_mean_squares(const Samples& samples, const Eigen::VectorXd& left, double window) {
  Stretches out;
  const double period = (samples.t.back() - samples.t.front()) / static_cast<double>(samples.size() - 1);
  out.width = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(window / period)));
  for (std::size_t start = 0; start + out.width <= samples.size(); start += out.width)
    out.mean_square.push_back(
        joint_mean_square(left.segment(kNumJoints * static_cast<Eigen::Index>(start),
                                       kNumJoints * static_cast<Eigen::Index>(out.width))));
  return out;
}

Vector7 joint_mean_square(const Eigen::VectorXd& stacked) {
  const Eigen::Map<const Eigen::Matrix<double, kNumJoints, Eigen::Dynamic>> m(stacked.data(), kNumJoints,
                                                                              stacked.size() / kNumJoints);
  return m.rowwise().squaredNorm() / static_cast<double>(m.cols());
}

}  // namespace csp::gap
