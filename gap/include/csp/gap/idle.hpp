// Idle stretches: where the arm does not move, a log tells nothing about the motion's dynamics
// (the torque is the gravity torque of one pose), yet it fills the part it is in: a session log of
// `csp serve` is mostly the idle cycles before and after the motion, and a held-out half made of
// them judges every effect on standing still (a slow sensor drift then looks like thermal_drift).
// `csp gap` leaves the long ones out (docs/gap.md, "Idle stretches").
#pragma once

#include "csp/gap/signal.hpp"
#include "csp/io/joint_log.hpp"

namespace csp::gap {

struct IdleOptions {
  // [rad/s] The arm is idle while every joint's smoothed velocity (the diagnosis's own filter,
  // FilterOptions) stays below this: 10 times the filtered noise of the real Panda's velocity
  // (0.006 rad/s per sample, about 0.001 after the filter), well below any motion worth fitting
  // (the excitations reach 0.5-2 rad/s; a ramp from rest passes 0.01 rad/s within 0.1 s).
  double velocity = 0.01;
  // [s] Only stretches at least this long are left out: a motion's reversals and short stops,
  // where the static friction shows, stay in.
  double min_duration = 0.5;
  // [s] Of a stretch next to motion, this much is kept next to it: the filter window (0.1 s)
  // then sees the motion start from rest and come to rest as it was.
  double margin = 0.1;
};

// The log without its idle stretches, and how much was left out.
struct IdleTrim {
  JointLog log;                  // the rows kept; t closes the gaps (see leave_out_idle)
  double seconds_left_out = 0.0;
  int stretches = 0;             // idle stretches left out
};

// Whether a smoothed joint velocity is at rest.
bool at_rest(const Vector7& dq, const IdleOptions& options = {});

// Leaves out the idle stretches of `log` (the smoothed velocity of filter_log(log, filter)). The rows
// after a stretch left out inside the log move back in time by its length, one time step apart from
// the rows before it: the arm is at rest at the same pose on both sides, so the joined motion is
// continuous and the uniform grid does not bridge the stretch. Throws JointLogError naming the log
// when it is idle throughout (nothing to diagnose) or too short for the filter.
IdleTrim leave_out_idle(const JointLog& log, const FilterOptions& filter, const IdleOptions& options = {});

// The fraction of `samples` at which the arm is at rest (0 without samples).
double idle_fraction(const Samples& samples, const IdleOptions& options = {});

}  // namespace csp::gap
