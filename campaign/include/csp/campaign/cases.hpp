// A campaign's cases: its axes expanded into a deterministic list (a pure function of the file),
// and the one place a case's values are applied to a scenario.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "csp/campaign/campaign_file.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::campaign {

struct Case {
  int index = 0;
  std::string id;        // "c0007": sorts as the index does
  uint64_t seed = 0;     // the scenario's seed (sensor noise, lost commands), unless a `seed` axis sets it
  std::vector<std::pair<std::string, double>> parameters;   // in the axes' order
};

// The grid of the `values` axes (the first axis varies slowest), `runs` cases per grid point; the
// random axes drawn from each case's own generator (seeded by the campaign seed and the index).
std::vector<Case> expand_cases(const Campaign& campaign);

// Sets `parameter` to `value` in `scenario`; std::invalid_argument naming what is wrong for an
// unknown parameter or a value it cannot take. The names (docs/campaign.md):
//   seed                                  the scenario's seed (a whole number)
//   plant.mass_scale, plant.armature_scale, plant.friction_scale   the arm's, not the robot's model
//   plant.load_mass                       [kg] a payload the robot's model does not know
//   plant.armature.jN                     [kg m^2] joint N's rotor inertia (plant)
//   plant.friction.phi1|phi2|phi3.jN      joint N's Gaz friction law (N m, s/rad, rad/s; the plant's)
//   sensor.tau_J_bias.jN                  [N m] joint N's torque-sensor offset
//   controller.stiffness_scale, controller.damping_scale   joint impedance gains, scaled
//   controller.<number>                   translational_stiffness, rotational_stiffness, desired_force,
//                                         force_k_p, force_k_i, axis_damping, null_space_stiffness
//   faults.loss_probability, faults.latency_mean_us, faults.latency_jitter_us
//   scene.material.<name>.stiffness|damping|friction
//   scene.obstacle.<name>.breathing_amplitude [m], scene.obstacle.<name>.breathing_frequency_hz
void apply_parameter(rt::Scenario& scenario, const std::string& parameter, double value);

// The scenario of a case: its base (the `scenario` axis's, else the one) loaded afresh (a tissue
// keeps its state), the duration and the case's seed and parameters applied.
rt::Scenario case_scenario(const Campaign& campaign, const Case& c);
// The `scenario` axis's value `index` as the table shows it: as the campaign file wrote it.
std::string scenario_name(const Campaign& campaign, double index);

// cases.json: the campaign and its expanded cases, what every worker (a Slurm task on another
// machine) reads instead of the file.
std::string cases_json(const Campaign& campaign, const std::vector<Case>& cases);
void read_cases_json(const std::string& path, Campaign& campaign, std::vector<Case>& cases);

}  // namespace csp::campaign
