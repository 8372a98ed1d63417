// k-medoids of a set of joint configurations: the excitation anchors spread over the task's states
// (planning-notes section 1 (2)). PAM, Kaufman & Rousseeuw, "Finding Groups in Data" (1990), ch. 2:
// BUILD (greedy: each new medoid the point that lowers the summed distance most), then SWAP
// (exchange a medoid with a non-medoid while the best exchange lowers it), a local optimum that is
// the global one on most small sets. A small textbook implementation: no Debian package offers
// k-medoids to C++ (`apt-cache search medoid` finds none; FasterPAM's `kmedoids` and BanditPAM are
// PyPI packages).
#pragma once

#include <vector>

#include "csp/dynamics/model.hpp"

namespace csp::planners {

struct Medoids {
  std::vector<int> indices;   // into the points, ascending (the task's order when the points are a path)
  double cost = 0.0;          // sum over the points of the Euclidean distance to the nearest medoid [rad]
};

// The k medoids of `points` by PAM. Throws std::invalid_argument unless 1 <= k <= points.size().
Medoids k_medoids(const std::vector<Vector7>& points, int k);

// The summed distance of `points` to their nearest of `medoids` (indices into points).
double medoid_cost(const std::vector<Vector7>& points, const std::vector<int>& medoids);

}  // namespace csp::planners
