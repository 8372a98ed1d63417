// The excitation design (docs/excitation.md; planning-notes sections 1 and 4): a rest-to-rest
// Fourier series at an anchor whose free coefficients maximise identifiability, weighted toward a
// task's states, within the arm's limits with stated margins, collision-free when a clearance
// callback is given.
//
//   minimise   Phi = -(1/p) log det(A + eps I) + lambda log J_t      (A: the periods' information)
//   subject to every limit, sampled at `design_rate_hz` over one period, aggregated per joint and
//              kind by a smooth minimum (log-sum-exp) of normalised margins (<= the sampled minimum).
//
// 20 deterministic random starts (amplitude-scaled into the limits), the best one refined by NLopt's
// MMA (gradient-based, conservative: every outer iterate within the margins); the result is then checked at 1 kHz and, if anything is over, slowed down in closed form.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "csp/dynamics/limits.hpp"
#include "csp/dynamics/progress.hpp"
#include "csp/planners/fourier.hpp"
#include "csp/planners/identifiability.hpp"

namespace csp::planners {

// Fractions of the robot's limits the excitation may use, and absolute bounds (planning-notes section 1).
struct ExcitationLimits {
  double position_margin = 5.0 * 3.14159265358979323846 / 180.0;   // inside q_min/q_max [rad] (Gaz et al.)
  double dq = 0.6, ddq = 0.5, dddq = 0.5, tau = 0.7;                 // of dq_max (FR3: dq_upper/lower(q)), ddq_max, dddq_max, tau_max
  double dtau = 1000.0;                                              // [N m/s]
  double power = kDefaultPowerMax;                                   // joint_power, sum_j max(0, tau_j dq_j) [W]
  double tool_speed = 1.0;                                           // TCP speed [m/s]
};

// Peak use of each limit along a trajectory, as a fraction of what ExcitationLimits allows (<= 1: within).
struct LimitUsage {
  Vector7 q = Vector7::Zero();      // |q - middle| / (half range - margin)
  Vector7 dq = Vector7::Zero(), ddq = Vector7::Zero(), dddq = Vector7::Zero(), tau = Vector7::Zero(), dtau = Vector7::Zero();
  double power = 0.0, tool_speed = 0.0;
  double min_clearance = INFINITY;  // of the clearance callback [m]; infinity without one
  bool within() const;
  std::string worst() const;        // e.g. "tau joint 2: 1.03"
};

// Clearance of a state [m], >= 0 when valid (e.g. ClearanceChecker::check(q).clearance).
using ClearanceFunction = std::function<double(const Vector7&)>;

struct ExcitationOptions {
  Vector7 anchor = Vector7::Zero();   // rest pose at both ends of every period
  int harmonics = 5;
  double fundamental_hz = 0.1;
  int periods = 3;
  double design_rate_hz = 20.0;
  // The task states the identification should serve; empty: whole-workspace D-optimal design.
  std::vector<JointSample> task;
  double task_weight = 1.0;           // lambda
  // kConditionNumber: minimise condition_criterion (a smooth log kappa) instead of Phi; the task
  // samples are then only reported on (J_t, r_t), not weighted.
  enum class Design { kInformation, kConditionNumber };
  Design design = Design::kInformation;
  // The information W^T W^ of what the plan already identifies (the segments at earlier anchors,
  // ExcitationProblem::information), added to this segment's: A = prior + P W^_1^T W^_1. Empty: none.
  Eigen::MatrixXd prior_information;
  ExcitationLimits limits;
  ClearanceFunction clearance;        // optional
  double clearance_buffer = 0.005;    // [m] asked of the design samples on top of clearance >= 0 (motion between them)
  unsigned seed = 1;
  int random_starts = 20;
  int max_evaluations = 300;          // NLopt budget (criterion + constraints with gradients)
  double sharpness = 100.0;           // rho of the smooth minimum over normalised margins
  Progress progress;                  // "optimising", evaluations of max_evaluations
};

// The criteria of a trajectory: stacked regressor of its states at design_rate_hz over [0, duration).
struct ExcitationCriteria {
  double criterion = 0.0;             // Phi (lower is better)
  Identifiability identifiability;
};

struct ExcitationResult {
  FourierSeries series;               // rest to rest at the anchor, after time scaling
  double time_scale = 1.0;            // k >= 1 applied after the optimisation (1: none needed)
  double amplitude_scale = 1.0;       // < 1: shrunk toward the anchor because the 1 kHz check found a contact
  double duration = 0.0;              // periods / fundamental [s]
  ExcitationCriteria criteria;
  LimitUsage usage;                   // at 1 kHz over one period
  double best_start_criterion = 0.0;  // the best of the random starts
  int evaluations = 0;                // NLopt evaluations
  std::string optimizer_result;       // NLopt's stopping reason
};

class ExcitationProblem {
 public:
  // `model`: the arm with the tool the excitation carries (with_tool). Throws std::invalid_argument
  // naming the bad option (anchor outside the margins, harmonics < 2, ...).
  ExcitationProblem(const Model& model, ExcitationOptions options);

  ExcitationResult solve() const;

  // The pieces, public for the tests, the benchmark and the baselines:
  const IdentificationModel& identification() const { return id_; }
  const ExcitationOptions& options() const { return options_; }
  int variables() const { return kNumJoints * (2 * options_.harmonics - 3); }
  FourierSeries series(const std::vector<double>& x) const;
  // Phi of the free coefficients x over the design samples, and dPhi/dx when gradient != nullptr
  // (analytic through the Fourier terms and the criterion; forward differences of the regressor in
  // the state, 21 extra regressor evaluations per sample).
  double criterion(const std::vector<double>& x, std::vector<double>* gradient) const;
  // Smooth-minimum margins per constraint (>= 0: every design sample within), and their gradient
  // (row-major, constraints x variables) when jacobian != nullptr.
  std::vector<double> margins(const std::vector<double>& x, std::vector<double>* jacobian) const;
  std::vector<std::string> margin_names() const;
  // Start `index` of the multistart: seeded uniform coefficients in [-1, 1] rad/s, shrunk by bisection
  // on a common factor until every design margin is >= 0.
  std::vector<double> random_start(unsigned index) const;

  // Criteria of any trajectory over `duration` (the baselines: random series, Gaz et al.'s), with
  // the prior information: those of the plan so far.
  ExcitationCriteria evaluate(const FourierSeries& series, double duration) const;
  // W^T W^ of the trajectory's states at design_rate_hz over [0, duration) (no prior).
  Eigen::MatrixXd information(const FourierSeries& series, double duration) const;
  // Peak limit use over [0, duration] at rate_hz.
  LimitUsage usage(const FourierSeries& series, double duration, double rate_hz = 1000.0) const;

 private:
  Model model_;
  ExcitationOptions options_;
  IdentificationModel id_;
  Eigen::MatrixXd task_information_;   // W^_t^T W^_t
  int task_rows_ = 0;
  // Design samples over one period: row k holds B^T phi(t_k), so that q_j(t_k) - anchor_j = row . free_j
  // (and the same for dq, ddq, dddq).
  Eigen::MatrixXd design_q_, design_dq_, design_ddq_, design_dddq_;

  JointSample design_state(const Eigen::MatrixXd& free, int k) const;
  // Phi (or the condition criterion, options_.design) of the information A and dPhi/dA.
  Criterion design_value(const Eigen::MatrixXd& A, double lambda) const;
  // d/dx of a quantity of sample k whose derivatives in (q, dq, ddq) are `ds` (1 x 21).
  Eigen::VectorXd chain(const Eigen::Matrix<double, 1, 3 * kNumJoints>& ds, int k) const;
};

// Excitations at several anchors (each its own rest-to-rest segment), designed one after the other:
// anchor a's series minimises the criterion of the information of segments 1..a (sequential
// design: the prior is what segments 1..a-1 identify), so Phi, J_t and the condition number are
// the whole plan's. `options.anchor` and `options.prior_information` are replaced per anchor; the
// seed is options.seed + a.
struct MultiAnchorExcitation {
  std::vector<ExcitationResult> segments;   // in the order of the anchors; segments[a].criteria: segments 1..a
  ExcitationCriteria criteria;              // of all segments together
};
MultiAnchorExcitation solve_anchors(const Model& model, const ExcitationOptions& options, const std::vector<Vector7>& anchors);

// t -> t/k: the same path k times slower, FourierSeries(f/k, a/k, b/k, q0). Without friction the
// torque becomes tau_k = g + (tau_1 - g)/k^2 (Hollerbach 1984).
FourierSeries time_scaled(const FourierSeries& series, double k);

// The smallest k (closed form, Hollerbach 1984; may be < 1: faster) that brings the series within
// the rate limits (dq, ddq, dddq, tau, dtau, power, tool speed; positions do not change with time):
// k = max_j max(dq/dq_lim, sqrt(ddq/ddq_lim), cbrt(dddq/dddq_lim), sqrt(|tau_1 - g|/(tau_lim - |g| - |tau_f|)),
// dtau/dtau_lim, power/power_lim, v/v_lim) from samples at rate_hz over one period, then raised by
// 1 % steps until a re-check at rate_hz passes (friction and the power and dtau bounds are not exact
// power laws of k). Throws std::runtime_error if no k <= 1000 fits (e.g. gravity alone above the torque limit).
double time_scale_into_limits(const ExcitationProblem& problem, const FourierSeries& series, double rate_hz = 1000.0);

}  // namespace csp::planners
