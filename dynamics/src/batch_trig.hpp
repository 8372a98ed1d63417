// The vectorised sin/cos of many angles (src/joint_trig.cpp). Internal header.
#pragma once

#include <cstddef>

namespace csp::detail {

// sin and cos of n angles, n a multiple of 4 (four per libmvec call).
void sin_cos_in_fours(const double* theta, double* sin_theta, double* cos_theta, std::ptrdiff_t n);

}  // namespace csp::detail
