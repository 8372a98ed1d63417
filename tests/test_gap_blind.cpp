// The diagnosis run blind on generated "real" logs whose truth has effects the diagnosing model
// lacks: it must name the injected effect for every effect of the library (three seeds each) and
// nothing when nothing was injected; with two effects injected it must name both, larger first.
// Training and held-out logs are different excitation trajectories, 10 s each at 1 kHz, with
// the real log's noise levels.
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "csp/gap/diagnosis.hpp"
#include "csp/gap/generator.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using namespace csp::gap;

#if defined(__SANITIZE_ADDRESS__)
// The sanitizer build runs 10-20x slower: one seed per effect and the first three pairs there.
constexpr unsigned kSeeds = 1;
constexpr std::size_t kPairs = 3;
constexpr unsigned kOutsideSeeds = 1;
#else
constexpr unsigned kSeeds = 3;
constexpr std::size_t kPairs = 10;
constexpr unsigned kOutsideSeeds = 3;
#endif

Model diagnosing_model() {
  ModelOptions options;
  options.friction = "none";
  return make_model("panda", options);
}

// Training and held-out logs of one truth; `seed` picks the effect's size, trajectories and noise.
Diagnosis diagnose_blind(const Model& model, const InjectedEffects& truth, unsigned seed) {
  const JointLog train = generate_log(model, truth, 100 * seed + 1, 100 * seed + 2);
  const JointLog heldout = generate_log(model, truth, 100 * seed + 3, 100 * seed + 4);
  return diagnose(model, train, heldout);
}

std::string verdict(const Diagnosis& d) {
  if (d.causes.empty()) return "none";
  std::string out;
  for (const std::string& c : d.causes) out += (out.empty() ? "" : "+") + c;
  return out;
}

TEST(GapBlind, NamesEachInjectedEffectAndNothingForNone) {
  const Model model = diagnosing_model();
  std::vector<std::string> truths = {"none"};
  truths.insert(truths.end(), kEffectNames.begin(), kEffectNames.end());
  std::map<std::string, std::map<std::string, int>> confusion;  // truth -> verdict -> count
  int misses = 0;
  for (const std::string& truth : truths)
    for (unsigned seed = 1; seed <= kSeeds; ++seed) {
      const std::string named = verdict(diagnose_blind(model, realistic_effect(truth, model, seed), seed));
      ++confusion[truth][named];
      if (named != truth) {
        ++misses;
        ADD_FAILURE() << "truth " << truth << ", seed " << seed << ": named " << named;
      }
    }
  std::ostringstream table;
  table << "confusion matrix (rows: injected, columns: named; " << kSeeds << " seeds)\n" << std::setw(20) << "";
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

// The mean square of an effect's torque on the held-out trajectory (noise-free truth minus the
// noise-free diagnosing model): the reference for which of two effects is larger.
double contribution(const Model& model, const InjectedEffects& effect, unsigned seed) {
  const LogOptions quiet = noise_free({});
  const JointLog with = generate_log(model, effect, 100 * seed + 3, 100 * seed + 4, quiet);
  const JointLog without = generate_log(model, {}, 100 * seed + 3, 100 * seed + 4, quiet);
  double sum = 0.0;
  for (std::size_t k = 0; k < with.size(); ++k) sum += (with.tau_J[k] - without.tau_J[k]).squaredNorm();
  return sum / static_cast<double>(with.size());
}

TEST(GapBlind, PairsAreBothNamedLargerFirst) {
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
  for (std::size_t i = 0; i < kPairs; ++i) {
    const unsigned seed = 11 + static_cast<unsigned>(i);
    const InjectedEffects a = realistic_effect(pairs[i].first, model, seed),
                          b = realistic_effect(pairs[i].second, model, seed);
    const double size_a = contribution(model, a, seed), size_b = contribution(model, b, seed);
    const std::string expected =
        size_a >= size_b ? pairs[i].first + "+" + pairs[i].second : pairs[i].second + "+" + pairs[i].first;
    const std::string named = verdict(diagnose_blind(model, merged(a, b), seed));
    std::cout << "pair " << pairs[i].first << " (" << std::sqrt(size_a) << " N m rms) + " << pairs[i].second << " ("
              << std::sqrt(size_b) << " N m rms): named " << named << '\n';
    EXPECT_EQ(named, expected);
  }
}

// An effect outside every library (a structural vibration at a fixed frequency): no cause may be
// named for it, and the unexplained part must be localised to its joint as periodic in time at its
// frequency.
TEST(GapBlind, LocalisesWhatNoLibraryEffectExplains) {
  const Model model = diagnosing_model();
  for (unsigned seed = 1; seed <= kOutsideSeeds; ++seed) {
    const InjectedEffects truth = outside_library_effect(seed);
    const Diagnosis d = diagnose_blind(model, truth, seed);
    EXPECT_EQ(verdict(d), "none") << "seed " << seed;
    ASSERT_FALSE(d.unexplained.empty()) << "seed " << seed;
    const UnexplainedStructure& top = d.unexplained.front();
    std::cout << "vibration " << truth.vibration_amplitude << " N m at " << truth.vibration_frequency << " Hz on joint "
              << truth.vibration_joint << ": " << top.detail << '\n';
    EXPECT_EQ(top.joint, truth.vibration_joint);
    EXPECT_EQ(top.kind, "time_periodic");
    EXPECT_NEAR(top.value, truth.vibration_frequency, 0.05);
    // The smoothing filter passes 2-3 Hz with a gain of 0.98-1: the size is the amplitude / sqrt(2).
    EXPECT_NEAR(top.size, truth.vibration_amplitude / std::sqrt(2.0), 0.1 * truth.vibration_amplitude);
  }
}

}  // namespace
}  // namespace csp::test
