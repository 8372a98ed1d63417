// The diagnosing (simulator) model evaluated along one part of a log: predicted torque, residual,
// and the regressors the candidate effects are built from. Stacked vectors and matrices have one
// row per sample and joint: row 7 k + j is joint j of sample k.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"
#include "csp/dynamics/regressor.hpp"
#include "csp/gap/signal.hpp"

namespace csp::gap {

struct Part {
  Samples samples;
  std::vector<Vector7> predicted;  // model torque tau = M ddq + c + g + friction (the simulator)
  Eigen::VectorXd residual;        // measured - predicted, stacked
  Eigen::MatrixXd inertial;        // the inertial regressor, stacked (7 N x 70)
  Eigen::MatrixXd tilt;            // torque per radian of base tilt about base x and y (7 N x 2)
  std::vector<Vector7> gravity;    // g(q) of the model
  Eigen::Index rows() const { return residual.size(); }
};

Part evaluate_part(const Model& model, Samples samples);

// The samples of `part` where keep[k] (the uniform grid stays whole: the fast laws run along it).
Part subset(const Part& part, const std::vector<bool>& keep);

// Stack / unstack per-sample joint vectors.
Eigen::VectorXd stack(const std::vector<Vector7>& series);
Vector7 joint_mean_square(const Eigen::VectorXd& stacked);

// A part's residual `left` (stacked) cut into consecutive stretches of about `window` seconds (the
// rest dropped): `width` samples each, and each stretch's mean square per joint.
struct Stretches {
  std::size_t width = 1;
  std::vector<Vector7> mean_square;
};
Stretches stretch_mean_squares(const Samples& samples, const Eigen::VectorXd& left, double window);

}  // namespace csp::gap
