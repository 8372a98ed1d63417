#include "base_frame.hpp"
#include "csp/dynamics/algorithms.hpp"

namespace csp {

// Composite-rigid-body algorithm in base coordinates (Featherstone Table 6.2): with I^c_k the
// inertia of bodies k..7, M_jk = S_j . (I^c_k S_k) for j <= k.
void crba(const Model& model, Data& data, const Vector7& q) {
  forward_kinematics(model, data, q);
  detail::update_base_inertias(model, data);
  SpatialInertia composite;
  for (int k = kNumJoints - 1; k >= 0; --k) {
    composite += data.O_inertia[k];
    data.composite[k] = composite;
    const Vector6 F = composite * data.axis[k];
    for (int j = 0; j <= k; ++j) data.mass_matrix(j, k) = data.mass_matrix(k, j) = data.axis[j].dot(F);
  }
}

}  // namespace csp
