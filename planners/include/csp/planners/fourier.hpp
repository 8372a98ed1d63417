// Excitation trajectories as finite Fourier series per joint (Swevers, Ganseman, Tukel, De Schutter
// & Van Brussel, IEEE TRA 13(5), 1997), with f = fundamental_hz, w = 2 pi f, harmonics l = 1..N:
//
//   q_j(t)    = q0_j + sum_l [ a_jl/(w l) sin(w l t) - b_jl/(w l) cos(w l t) ]
//   dq_j(t)   = sum_l [ a_jl cos(w l t) + b_jl sin(w l t) ]
//   ddq_j(t)  = sum_l w l [ -a_jl sin(w l t) + b_jl cos(w l t) ]
//   dddq_j(t) = -sum_l (w l)^2 [ a_jl cos(w l t) + b_jl sin(w l t) ]
//
// Periodic with period 1/f, so that averaging periods cuts noise and derivatives are exact.
#pragma once

#include <functional>
#include <string>

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"

namespace csp::planners {

using Coefficients = Eigen::Matrix<double, kNumJoints, Eigen::Dynamic>;   // row j: joint j, column l-1: harmonic l

struct JointSample {
  Vector7 q = Vector7::Zero(), dq = Vector7::Zero(), ddq = Vector7::Zero(), dddq = Vector7::Zero();
};

// Bounds that hold for every t, from rho_jl = sqrt(a_jl^2 + b_jl^2):
// |q - q0| <= sum rho/(w l), |dq| <= sum rho, |ddq| <= w sum l rho, |dddq| <= w^2 sum l^2 rho.
struct FourierBounds {
  Vector7 q_deviation, dq, ddq, dddq;
};

class FourierSeries {
 public:
  // a, b: 7 x N [rad/s]; fundamental_hz > 0, N >= 1 (throws std::invalid_argument otherwise).
  FourierSeries(double fundamental_hz, Coefficients a, Coefficients b, const Vector7& q0);

  // Rest to rest at `anchor`: q = anchor and dq = ddq = dddq = 0 at t = 0 and at every period end.
  // The conditions sum_l a_jl = 0, sum_l l b_jl = 0, sum_l l^2 a_jl = 0 are linear, so the
  // coefficients are [a_j b_j] = free_j B^T with B an orthonormal basis of their null space
  // (rest_to_rest_basis): 2N-3 free numbers per joint (free: 7 x (2N-3)), and
  // q0_j = anchor_j + sum_l b_jl/(w l).
  static FourierSeries rest_to_rest(double fundamental_hz, int harmonics, const Eigen::MatrixXd& free,
                                    const Vector7& anchor);

  // Sample at time t [s]; allocates nothing.
  JointSample sample(double t) const;
  FourierBounds bounds() const;

  double fundamental_hz() const { return fundamental_hz_; }
  double period() const { return 1.0 / fundamental_hz_; }
  int harmonics() const { return static_cast<int>(a_.cols()); }
  const Coefficients& a() const { return a_; }
  const Coefficients& b() const { return b_; }
  const Vector7& q0() const { return q0_; }

 private:
  double fundamental_hz_;
  double omega_;
  Coefficients a_, b_;
  Vector7 q0_;
};

// 2N x (2N-3) orthonormal basis of {(a_1..a_N, b_1..b_N) : sum a_l = 0, sum l b_l = 0, sum l^2 a_l = 0}
// (N >= 2; the SVD of the 3 x 2N condition matrix).
Eigen::MatrixXd rest_to_rest_basis(int harmonics);

// The series sampled at `rate_hz` over [0, duration] as a joint log (docs/joint-log.md): t, q, dq,
// ddq, and as tau_J the link-side torque the motion needs on `model` (RNEA with gravity plus the
// model's friction), what the torque sensor of a robot that is this model would read. Write it
// with write_joint_log_csv.
JointLog trajectory_log(const FourierSeries& series, double duration, double rate_hz, const Model& model);

// Any trajectory `sample(t)` sampled the same way (t = k / rate_hz, k = 0 .. floor(duration rate_hz)),
// tau_J as above; `source` names it in the log. trajectory_log above and the transfers' (profile.hpp) use it.
JointLog sampled_joint_log(const std::function<JointSample(double)>& sample, double duration, double rate_hz,
                           const Model& model, std::string source);

}  // namespace csp::planners
