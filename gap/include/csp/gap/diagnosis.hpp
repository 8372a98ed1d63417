// csp gap: where the simulator model misses a log of the real robot, which unmodelled effect is
// responsible, and how far the gap shrinks once it is added (docs/gap.md states the criteria).
#pragma once

#include <array>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/dynamics/progress.hpp"
#include "csp/gap/effects.hpp"
#include "csp/io/joint_log.hpp"

namespace csp::gap {

struct DiagnosisOptions {
  FilterOptions filter;
  double train_fraction = 0.5;    // of the log's duration, when there is no held-out log
  int null_draws = 20;            // random regressors per significance test (max of 20 ~ 95th percentile)
  double min_explained = 0.02;    // and an effect must remove at least this fraction of the held-out mean square
  double parsimony_margin = 0.1;  // a smaller effect within this fraction of the best improvement is preferred
  unsigned seed = 1;              // of the random regressors
  Progress progress;              // its stages: each effect alone, each selection step, the checks
};

// One effect (or set) fitted on the training part and evaluated on the held-out part.
struct EffectResult {
  std::string name;
  int parameter_count = 0;
  std::vector<int> joints;  // 1-based: joints whose held-out mean square it reduces by >= 10 %
  nlohmann::json params;
  Vector7 train_rms_after = Vector7::Zero(), heldout_rms_after = Vector7::Zero();
  double explained_fraction = 0.0;  // of the held-out mean square it started from, clipped to 0..1
  std::array<double, 2> explained_fraction_interval{};  // its block-bootstrap interval (docs/gap.md, "Uncertainty")
  double judged_fraction = 0.0;     // of it, what it removes within the excitation band (the significance's)
  double null_threshold = 0.0;      // best held-out improvement of the random regressors of its size
  bool significant = false;
};

// "Where it lies": the residual of one joint over both parts.
struct JointGap {
  double rms = 0.0, mean = 0.0, max_abs = 0.0, t_at_max = 0.0;
  std::string part_at_max;                    // "train" or "heldout"
  double sign_step = 0.0;                     // mean residual at dq > 0.05 rad/s minus at dq < -0.05 rad/s
  std::map<std::string, double> correlation;  // with q, dq, sign(dq), ddq, gravity torque
  std::array<double, 4> band_fraction{};      // residual power below 0.5, 0.5-2, 2-5, above 5 Hz
};
inline constexpr std::array<double, 3> kBandEdges = {0.5, 2.0, 5.0};

// The noise floor of one joint's residual left after the verdict: the broadband level of its
// spectrum (unexplained.cpp, noise_floor), split between the two sides of residual =
// measured - model by the same levels of their own spectra (docs/gap.md, "Noise floor").
struct NoiseFloor {
  double rms = 0.0;              // [N m] the residual's noise
  double measured_rms = 0.0;     // its part in the measured torque: the sensor's noise
  double model_input_rms = 0.0;  // its part in the model's torque: the noise of its inputs (ddq from dq)
};

// What the verdict leaves unexplained, localised: a structure of one joint's held-out residual
// standing above the noise floor (docs/gap.md lists the kinds and the rules).
struct UnexplainedStructure {
  int joint = 0;        // 1-based
  std::string kind;     // offset, time_drift, position_periodic, velocity_sign, velocity, hysteresis,
                        // acceleration, torque_level, torque_of_joint, velocity_of_joint,
                        // position_of_joint, time_periodic, motion_periodic, band, transient,
                        // reversal_event, position_event (events.hpp)
  double size = 0.0;    // RMS of the structure's torque [N m]
  double share = 0.0;   // of the joint's remaining held-out mean square it accounts for
  double value = 0.0;   // the structure's parameter: period [rad], frequency [Hz], slope, start [s],
                        // the share of reversals with a burst, the position of the bursts [rad] ...
  double floor_multiple = 0.0;             // size / what the noise floor alone puts in the same kind (band)
  double band_low = 0.0, band_high = 0.0;  // [Hz] the band of the spectral kinds (0 for the others)
  std::string side;     // measured_torque (a torque the robot has and the model lacks, or the sensor's)
                        // or model_input (in the model's prediction: the noise its inputs carry in)
  int from_joint = 0;   // torque_of_joint, velocity_of_joint, position_of_joint: the joint driving it;
                        // reversal_event, position_event: the joint whose motion it follows
  std::vector<double> times;  // reversal_event, position_event: each burst [s], in its part's time
  std::vector<bool> times_in_heldout;  // per burst: in the held-out part (else the training part)
  // A band shared with other joints (one mode): the joints whose residual is coherent with this one's
  // in its band, this one included (also those where it stays below what is reported alone), each
  // one's phase relative to this one's [deg] and coherence; empty when on this joint alone.
  std::vector<int> mode_joints;
  std::vector<double> mode_phase_deg;
  std::vector<double> mode_coherence;  // magnitude-squared coherence with `joint` in the band (1 for itself)
  std::string detail;   // one plain sentence
};
inline constexpr const char* kMeasuredTorque = "measured_torque";
inline constexpr const char* kModelInput = "model_input";

// A short disturbance in one part: a few stretches of the residual left after the causes far above
// the rest (docs/gap.md, "Backward check").
inline constexpr double kTransientWindow = 0.5;  // [s] the stretches
inline constexpr double kTransientRatio = 10.0;  // mean square above this many times the median stretch's
inline constexpr double kTransientShare = 0.25;  // at most this fraction of a part's stretches, or it is no transient
struct Transient {
  bool heldout = false;          // in the held-out part (else the training part)
  double start = 0.0, end = 0.0; // [s], the log's time
  int joint = 0;                 // 1-based: the joint it is largest on
  double size = 0.0;             // RMS of the residual left on that joint during it [N m]
  double share = 0.0;            // of that joint's mean square left in its part
};

// A cause whose size changes along the log (docs/gap.md, "Drift"): in kDriftStretches stretches of
// each part, each cause's gain on each joint (the scale of its verdict torque that fits there; 1 = as
// on the whole); a gain that follows a line in time beyond its scatter about it (Student's t,
// two-sided, below kDriftFalseAlarm over all causes and joints) and changes by at least kDriftChange
// over the log drifts.
inline constexpr int kDriftStretches = 10;          // per part (20 in all: the line has 18 degrees of freedom)
inline constexpr double kDriftFalseAlarm = 1e-3;    // per diagnosis (Bonferroni over causes and joints)
inline constexpr double kDriftChange = 0.1;         // [-] of the gain, over the log
struct EffectDrift {
  std::string effect;                 // the cause
  int joint = 0;                      // 1-based
  std::vector<double> times, gains;   // each stretch's mid-time [s] and the cause's torque gain there
  double per_minute = 0.0;            // the line's slope [1/min]
  double change = 0.0;                // the line's change over the stretches' span
  double p_value = 1.0;               // of a slope this large by chance
  std::string detail;                 // one plain sentence
};

struct Diagnosis {
  Part train, heldout;
  Vector7 baseline_train_rms = Vector7::Zero(), baseline_heldout_rms = Vector7::Zero();
  std::array<JointGap, kNumJoints> where;
  std::vector<EffectResult> effects;  // each effect alone, best held-out improvement first
  std::vector<EffectResult> steps;    // forward selection: the set after each added cause
  std::vector<std::string> causes;    // the selected effects, most important first
  std::vector<std::string> dropped;   // selected, then dropped: not significant once the later causes were in
  Vector7 verdict_heldout_rms_after = Vector7::Zero();
  double unexplained_fraction = 1.0;       // held-out mean square left by the selected causes
  std::array<double, 2> unexplained_fraction_interval = {1.0, 1.0};  // its block-bootstrap interval
  // What the causes left of the held-out part with their unconstrained fit, when it was not physical (a
  // linear inertial fit no physical links realise, a negative viscous friction) and the verdict is the
  // constrained refit (docs/gap.md); NaN otherwise.
  double unconstrained_unexplained_fraction = std::numeric_limits<double>::quiet_NaN();
  nlohmann::json verdict_params;           // the causes' parameters fitted together, with their intervals
  Eigen::VectorXd verdict_heldout_torque;  // the causes' torque on the held-out part (stacked)
  std::vector<UnexplainedStructure> unexplained;  // strongest first (transients too, kind "transient")
  std::vector<Transient> transients;              // left out of the backward check
  std::array<NoiseFloor, kNumJoints> noise_floor; // of the held-out residual left
  // The held-out mean square left (unexplained_fraction of the baseline's), split: the measured
  // torque's noise floor; the model's input (its noise floor and its bands above the floor); the rest.
  double unexplained_noise = 0.0, unexplained_model_input = 0.0, unexplained_rest = 0.0;
  std::vector<std::string> warnings;              // fits that are not physical (docs/gap.md)
  std::vector<EffectDrift> drifts;                // the causes whose size changes along the log
};

// The residual `left` (stacked, on `part`) after the verdict: its noise floor per joint and its
// structures above it, at most kMaxStructures per joint, each found on what the stronger ones left
// and at least kUnexplainedSize of torque and kUnexplainedShare of the joint's mean square left;
// `causes` are the selected effects (a structure a library effect could model but which was not
// selected says so).
inline constexpr double kUnexplainedSize = 0.03, kUnexplainedShare = 0.1;  // [N m], [-]
inline constexpr int kMaxStructures = 3;
struct Localisation {
  std::array<NoiseFloor, kNumJoints> floor;
  std::vector<UnexplainedStructure> structures;  // strongest first
};
Localisation localise_unexplained(const Part& part, const Eigen::VectorXd& left, const std::vector<std::string>& causes);

Diagnosis diagnose(const Model& model, const JointLog& train, const JointLog& heldout,
                   const DiagnosisOptions& options = {});
// Splits one log in time: the first train_fraction for training, the rest held out.
Diagnosis diagnose(const Model& model, const JointLog& log, const DiagnosisOptions& options = {});

// The output contract of `csp gap --json` (docs/gap.md).
nlohmann::json to_json(const Diagnosis& diagnosis);

Vector7 rms(const Eigen::VectorXd& stacked);

}  // namespace csp::gap
