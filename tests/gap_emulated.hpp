// The blind check's second generator: "real" logs made by the emulated robot (rt/) instead of the
// dynamics core alone, so that its torque loop, its torque sensor's noise, the controller's
// tracking errors and the integrator stand between the injected effect and the log. Library
// csp_gap_emulated (tests/): it needs rt and gap, and gap depends on the dynamics core only, so it
// lives with the tests that use it, not in gap/ (docs/gap.md, "Checked on data whose effect is withheld").
#pragma once

#include "csp/gap/generator.hpp"

namespace csp::test {

// A log of the emulated robot whose plant is the diagnosing model plus `truth`, tracking the
// Fourier excitation of `trajectory_seed` with the default scenario's joint impedance controller
// (libfranka's joint_impedance_control gains, model feed-forward by the robot's model = the
// diagnosing model). Where each injected effect goes:
// - the plant, natively: friction (sliding and static), armature, payload, true links, base tilt;
// - the plant's extra joint torque (rt::PlantTorque): position ripple, Dahl friction, load-
//   dependent friction and the outside-library vibration (gap::InjectedJointTorque). Dahl's friction
//   goes in whole (a z): the library's effect, its part beyond the sliding law, is an anti-friction
//   near rest that the closed loop cannot carry; so the log shows joint_friction with it;
// - the torque sensor: the offset and the noise are the emulator's (tau_J_bias, tau_J_noise, seeded
//   by `noise_seed`); delay, gain and drift, which the emulator does not model, are applied to its
//   reading here: reading(t) = (1 + g) tau_J(t - d) + r t. Encoder noise (the emulator's encoders
//   are exact) is added to q and dq at options' levels.
// The arm starts at rest at the series' centre and the reference ramps in over kRampIn; the log
// covers options.duration from the end of the ramp at the emulator's 1 kHz (options.rate is not
// used). Throws std::runtime_error if the motion ends in a reflex, or std::invalid_argument if both
// the model and the truth have a sliding friction law (the plant has one).
inline constexpr double kRampIn = 3.0;  // [s]
JointLog generate_emulated_log(const Model& model, const gap::InjectedEffects& truth, unsigned trajectory_seed,
                               unsigned noise_seed, const gap::LogOptions& options = {});

}  // namespace csp::test
