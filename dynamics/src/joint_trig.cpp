// sin and cos of the seven joint angles in one vectorised pass. Scalar sin/cos cost about 20 ns
// each here, more than the rest of an RNEA; glibc's vector math library (libmvec) does four at a
// time. GCC only calls libmvec under -ffast-math, so this file alone is built with it (CMakeLists);
// it holds nothing but these loops, so no other arithmetic is affected.
#include "steps.hpp"

#include <cmath>

namespace csp::detail {

void joint_sin_cos(const Vector7& theta, Vector7& sin_theta, Vector7& cos_theta) {
  // Padded to 8 lanes: two full 4-wide calls instead of 4 + 2 + a scalar remainder. Two loops,
  // because GCC fuses sin and cos of one argument into a scalar sincos call, which has no vector form.
  alignas(64) double in[8] = {}, s[8], c[8];
  for (int i = 0; i < kNumJoints; ++i) in[i] = theta[i];
#pragma omp simd
  for (int i = 0; i < 8; ++i) s[i] = std::sin(in[i]);
#pragma omp simd
  for (int i = 0; i < 8; ++i) c[i] = std::cos(in[i]);
  for (int i = 0; i < kNumJoints; ++i) {
    sin_theta[i] = s[i];
    cos_theta[i] = c[i];
  }
}

// The same 4-wide libmvec calls over many angles (batch.cpp: every joint of every state of a batch).
// n is a multiple of 4, so no angle falls into a scalar remainder and each result is the one
// joint_sin_cos gives for that angle.
void sin_cos_in_fours(const double* theta, double* sin_theta, double* cos_theta, std::ptrdiff_t n) {
#pragma omp simd simdlen(4)
  for (std::ptrdiff_t i = 0; i < n; ++i) sin_theta[i] = std::sin(theta[i]);
#pragma omp simd simdlen(4)
  for (std::ptrdiff_t i = 0; i < n; ++i) cos_theta[i] = std::cos(theta[i]);
}

}  // namespace csp::detail
