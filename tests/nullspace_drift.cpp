// csp_nullspace_drift: runs libfranka's cartesian_impedance_control law (tests/nullspace_drift.hpp)
// on a scenario's robot and prints the null-space drift per joint over time, and the null-space
// part of the gravity the robot's model gets wrong. Switches take the suspects out one at a time.
//
// usage: csp_nullspace_drift [--scenario FILE] [--duration S] [--matched-model] [--no-friction]
//                            [--no-static-friction] [--no-push]
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "csp/rt/scenario.hpp"
#include "nullspace_drift.hpp"

int main(int argc, char** argv) {
  std::string scenario_path = csp::rt::default_scenario_path();
  double duration = 60.0;
  bool matched_model = false, no_friction = false, no_static_friction = false, no_push = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--scenario" && i + 1 < argc) scenario_path = argv[++i];
    else if (arg == "--duration" && i + 1 < argc) duration = std::stod(argv[++i]);
    else if (arg == "--matched-model") matched_model = true;
    else if (arg == "--no-friction") no_friction = true;
    else if (arg == "--no-static-friction") no_static_friction = true;
    else if (arg == "--no-push") no_push = true;
    else {
      std::cerr << "usage: csp_nullspace_drift [--scenario FILE] [--duration S] [--matched-model] [--no-friction] "
                   "[--no-static-friction] [--no-push]\n";
      return 2;
    }
  }
  try {
    csp::rt::EmulatorSettings settings = csp::rt::load_scenario(scenario_path).emulator;
    if (no_friction) settings.plant.friction = csp::FrictionModel{};
    if (no_static_friction) settings.plant.friction.breakaway.setZero();
    if (no_push) settings.external_wrenches.clear();
    if (matched_model) settings.internal = settings.plant;

    // What drives the self-motion at the start pose: the gravity the robot's model gets wrong,
    // projected on the null-space direction n, against the static friction that can hold it.
    const csp::Model plant(settings.plant), internal(settings.internal);
    csp::Data data;
    csp::Vector7 g_plant, g_internal;
    csp::gravity_torque(plant, data, settings.q_initial, g_plant);
    csp::gravity_torque(internal, data, settings.q_initial, g_internal);
    csp::forward_kinematics(internal, data, settings.q_initial);
    csp::Matrix6x7 jacobian;
    csp::zero_jacobian(data, csp::Frame::kEndEffector, jacobian);
    const csp::Vector7 n = csp::test::null_space_direction(jacobian);
    const csp::Vector7 gravity_error = g_plant - g_internal;
    std::printf("start pose: null-space direction n =");
    for (int j = 0; j < 7; ++j) std::printf(" %+.3f", n[j]);
    std::printf("\n");
    std::printf("gravity error g_plant - g_robot [N m]:");
    for (int j = 0; j < 7; ++j) std::printf(" %+.3f", gravity_error[j]);
    std::printf("\nnull-space torque n^T (g_plant - g_robot) = %+.3f N m; static friction can hold sum |n_j| breakaway_j = %.3f N m\n",
                n.dot(gravity_error), n.cwiseAbs().dot(settings.plant.friction.breakaway));

    const csp::test::DriftRun run = csp::test::run_cartesian_impedance(settings, duration, 5.0);
    std::printf("\n   t [s]   self-motion [rad]   |dp_EE| [mm]   q - q0 per joint [rad]\n");
    for (const csp::test::DriftSample& s : run.samples) {
      std::printf("%8.1f   %+17.4f   %12.3f  ", s.t, s.self_motion, s.position_error * 1e3);
      for (int j = 0; j < 7; ++j) std::printf(" %+.4f", s.q_change[j]);
      std::printf("\n");
    }
    std::printf("largest |q - q0| per joint [rad]:");
    for (int j = 0; j < 7; ++j) std::printf(" %.4f", run.largest_change[j]);
    std::printf("\n%s at t = %.3f s\n", run.reflex.empty() ? "ran to the end" : ("reflex: " + run.reflex).c_str(), run.end_time);
  } catch (const std::exception& e) {
    std::cerr << "csp_nullspace_drift: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
