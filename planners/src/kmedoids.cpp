#include "csp/planners/kmedoids.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

namespace csp::planners {
namespace {

// Summed distance to the nearest medoid, from the distance matrix.
double cost_of(const Eigen::MatrixXd& distance, const std::vector<int>& medoids) {
  double cost = 0.0;
  for (Eigen::Index i = 0; i < distance.rows(); ++i) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const int m : medoids) nearest = std::min(nearest, distance(i, m));
    cost += nearest;
  }
  return cost;
}

}  // namespace

double medoid_cost(const std::vector<Vector7>& points, const std::vector<int>& medoids) {
  double cost = 0.0;
  for (const Vector7& p : points) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const int m : medoids) nearest = std::min(nearest, (p - points[static_cast<std::size_t>(m)]).norm());
    cost += nearest;
  }
  return cost;
}

Medoids k_medoids(const std::vector<Vector7>& points, int k) {
  const int n = static_cast<int>(points.size());
  if (k < 1 || k > n)
    throw std::invalid_argument("k-medoids: k = " + std::to_string(k) + " must be from 1 to the number of points (" +
                                std::to_string(n) + ")");
  Eigen::MatrixXd distance(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) distance(i, j) = (points[static_cast<std::size_t>(i)] - points[static_cast<std::size_t>(j)]).norm();

  // BUILD: greedily the point that lowers the summed distance most (the first one: the 1-medoid).
  Medoids result;
  std::vector<int>& medoids = result.indices;
  while (static_cast<int>(medoids.size()) < k) {
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int candidate = 0; candidate < n; ++candidate) {
      if (std::find(medoids.begin(), medoids.end(), candidate) != medoids.end()) continue;
      medoids.push_back(candidate);
      const double c = cost_of(distance, medoids);
      medoids.pop_back();
      if (c < best_cost) best_cost = c, best = candidate;
    }
    medoids.push_back(best);
  }
  // SWAP: the best exchange of a medoid with a non-medoid, while it lowers the cost (strictly, so
  // that it ends; ties keep the earlier set).
  double cost = cost_of(distance, medoids);
  for (;;) {
    double best_cost = cost;
    int best_slot = -1, best_point = -1;
    for (int slot = 0; slot < k; ++slot)
      for (int point = 0; point < n; ++point) {
        if (std::find(medoids.begin(), medoids.end(), point) != medoids.end()) continue;
        const int kept = medoids[static_cast<std::size_t>(slot)];
        medoids[static_cast<std::size_t>(slot)] = point;
        const double c = cost_of(distance, medoids);
        medoids[static_cast<std::size_t>(slot)] = kept;
        if (c < best_cost - 1e-12 * cost) best_cost = c, best_slot = slot, best_point = point;
      }
    if (best_slot < 0) break;
    medoids[static_cast<std::size_t>(best_slot)] = best_point;
    cost = best_cost;
  }
  std::sort(medoids.begin(), medoids.end());
  result.cost = cost;
  return result;
}

}  // namespace csp::planners
