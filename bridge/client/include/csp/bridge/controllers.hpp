// The example controllers of the client processes (csp_lcm_float, csp_lcm_joint_impedance),
// plain rt::Controller functions: the same function runs against `csp serve` over LCM and
// in-process with rt::run_motion, which is how the tests compare the two.
#pragma once

#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::bridge {

// Gravity-compensated float: tau = -D dq (the robot adds gravity); motion_finished after `duration` [s].
rt::Controller float_controller(const Vector7& damping, double duration);

// Joint impedance tracking of `trajectory` around the pose the session starts from:
// tau = K (q_d - q) + D (dq_d - dq); motion_finished after `duration` [s].
rt::Controller joint_impedance_controller(const Vector7& stiffness, const Vector7& damping,
                                          const rt::RampedSineReference& trajectory, double duration);

// The example's settings (also used by the tests' in-process reference): libfranka's
// joint_impedance_control gains, and a smooth excitation of `amplitude` on every joint.
Vector7 example_joint_stiffness();
Vector7 example_joint_damping();
rt::RampedSineReference example_excitation(double amplitude);

}  // namespace csp::bridge
