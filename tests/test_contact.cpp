// Contact between the emulated arm and its scene (docs/contact.md), against physics: the force
// laws' closed forms (Hunt-Crossley's first integral, the regularised Coulomb law's creep speed),
// static equilibria of the whole plant, energy, the robot's estimate against the true wrench
// with the error its model mismatch predicts, reflexes as libfranka names them, bad input.
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>

#include "contact_support.hpp"
#include "csp/dynamics/contact.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/scenario.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using rt::Command;
using rt::ControlMode;
using rt::Emulator;

const Vector7 kReady = (Vector7() << 0.0, -M_PI / 4, 0.0, -3 * M_PI / 4, 0.0, M_PI / 2, M_PI / 4).finished();

std::string scene_path(const std::string& name) { return std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + name + ".yaml"; }

const Scene& ultrasound_scene() { return *shipped_ultrasound_scene(); }

const Material& shipped(const std::string& name) { return ultrasound_scene().materials.at(name); }

// ---------------------------------------------------------------------------------------------
// The laws

// A mass m hitting the material at v_in, integrated with classical RK4 at a step far below the
// contact time: the rebound speed and the deepest penetration.
struct Impact {
  double rebound = 0.0, max_penetration = 0.0;
};
Impact integrate_impact(const Material& m, double mass, double v_in) {
  double x = 0.0, v = v_in, deepest = 0.0;   // x: penetration, v = dx/dt
  const double omega = std::sqrt(hunt_crossley_stiffness(m, 0.01) / mass);
  const double h = 1e-4 / std::max(1.0, omega);
  auto acceleration = [&](double x_, double v_) { return -hunt_crossley_force(m, x_, v_) / mass; };
  do {
    const double k1x = v, k1v = acceleration(x, v);
    const double k2x = v + 0.5 * h * k1v, k2v = acceleration(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const double k3x = v + 0.5 * h * k2v, k3v = acceleration(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const double k4x = v + h * k3v, k4v = acceleration(x + h * k3x, v + h * k3v);
    x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    deepest = std::max(deepest, x);
  } while (x > 0.0);
  return {-v, deepest};
}

TEST(ContactLaw, ReboundAndDepthMatchHuntCrossleysFirstIntegral) {
  for (const char* name : {"abdomen", "thigh", "skull", "furniture"}) {
    const Material& m = shipped(name);
    for (const double v_in : {0.01, 0.1, 0.5}) {
      const double mass = 2.0;
      const Impact impact = integrate_impact(m, mass, v_in);
      const double l = 1.5 * m.damping;
      // m/l^2 (l v - ln(1 + l v)) + k x^(n+1)/(n+1) is constant (Marhefka & Orin 1999).
      const double depth = std::pow((m.exponent + 1.0) * mass / (l * l) * (l * v_in - std::log1p(l * v_in)) / m.stiffness,
                                    1.0 / (m.exponent + 1.0));
      EXPECT_NEAR(impact.rebound, hunt_crossley_rebound_speed(m.damping, v_in), 1e-6 * v_in) << name << " " << v_in;
      EXPECT_NEAR(impact.max_penetration, depth, 1e-5 * depth) << name << " " << v_in;
      // Hunt & Crossley's linear restitution e = 1 - alpha v_in, to first order in alpha v_in.
      const double e = impact.rebound / v_in, alpha_v = m.damping * v_in;
      EXPECT_NEAR(e, 1.0 - alpha_v, alpha_v * alpha_v + 1e-9) << name << " " << v_in;
      EXPECT_LT(e, 1.0);
    }
  }
}

TEST(ContactLaw, NoTensionAtSeparation) {
  const Material& m = shipped("abdomen");
  EXPECT_EQ(hunt_crossley_force(m, 0.01, -10.0), 0.0);   // pulled out faster than 1/(1.5 alpha): no pull
  EXPECT_EQ(hunt_crossley_force(m, 0.0, 1.0), 0.0);
  EXPECT_EQ(hunt_crossley_force(m, -0.01, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(hunt_crossley_force(m, 0.02, 0.0), m.stiffness * std::pow(0.02, 1.5));
}

TEST(ContactLaw, FrictionStaysInsideTheConeAndSlidesAtTheCoulombLevel) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 0.05);
  const double mu = 0.4, F_n = 12.0, v_s = 1e-3;
  for (int i = 0; i < 1000; ++i) {
    const Vector3 v(n(rng), n(rng), 0.0);
    const Vector3 F = regularized_friction(mu, F_n, v, v_s);
    EXPECT_LE(F.norm(), mu * F_n * (1 + 1e-12));
    EXPECT_LE(F.dot(v), 0.0);   // against the slip: dissipates
  }
  const Vector3 sliding = regularized_friction(mu, F_n, Vector3(0.1, 0.0, 0.0), v_s);
  EXPECT_NEAR(sliding.x(), -mu * F_n, 1e-4 * mu * F_n);
}

// A block on the surface under a constant tangential load F: below the cone it creeps at the
// law's steady speed v_s F / sqrt((mu F_n)^2 - F^2) (of the order of v_s), above it accelerates.
TEST(ContactLaw, SticksBelowTheConeWithCreepOfTheOrderOfTheRegularisationSpeed) {
  const double mu = 0.3, F_n = 10.0, v_s = 1e-3, mass = 1.0, h = 1e-5;
  for (const double fraction : {0.2, 0.5, 0.9}) {
    const double F = fraction * mu * F_n;
    double v = 0.0;
    for (int k = 0; k < 100000; ++k) v += h * (F + regularized_friction(mu, F_n, Vector3(v, 0, 0), v_s).x()) / mass;
    const double creep = v_s * F / std::sqrt(mu * F_n * mu * F_n - F * F);
    EXPECT_NEAR(v, creep, 1e-6) << fraction;
    EXPECT_LT(v, 3.0 * v_s);
  }
  double v = 0.0;
  const double F = 1.1 * mu * F_n;
  for (int k = 0; k < 100000; ++k) v += h * (F + regularized_friction(mu, F_n, Vector3(v, 0, 0), v_s).x()) / mass;
  EXPECT_NEAR(v, (F - mu * F_n) * 1.0 / mass, 0.01);   // slides: (F - mu F_n) t after 1 s
}

TEST(ContactLaw, MaterialProblemsNameTheField) {
  const Material good{5300, 1.5, 1.0, 0.15};
  EXPECT_FALSE(material_problem(good));
  auto key_of = [](Material m) { return std::string(material_problem(m).value().key); };
  Material m = good;
  m.stiffness = -1.0;
  EXPECT_EQ(key_of(m), "stiffness");
  m = good;
  m.stiffness = std::numeric_limits<double>::infinity();
  EXPECT_EQ(key_of(m), "stiffness");
  m = good;
  m.exponent = 0.5;
  EXPECT_EQ(key_of(m), "exponent");
  m = good;
  m.damping = std::nan("");
  EXPECT_EQ(key_of(m), "damping");
  m = good;
  m.friction = -0.1;
  EXPECT_EQ(key_of(m), "friction");
}

// ---------------------------------------------------------------------------------------------
// The arm in contact

// Plant == internal model: the Panda (gaz2019 inertia, no joint friction) carrying the ultrasound
// probe, at the ready pose; `gravity` off makes the arm and its motion conservative.
rt::EmulatorSettings probe_settings(bool gravity = true) {
  ModelOptions o;
  o.inertia = "gaz2019";
  o.friction = "none";
  if (!gravity) o.gravity = Vector3::Zero();
  rt::EmulatorSettings s;
  s.plant = with_tool(model_parameters(load_robot_config(robot_file("panda")), o), ultrasound_scene().tool);
  s.internal = s.plant;
  s.q_initial = kReady;
  raise_collision_thresholds(s.collision);
  return s;
}

// A scene of one flat surface of `material`, `gap` [m] below the probe's tip at the ready pose: the
// top of a 0.3 x 0.3 x 0.1 m slab centred under the tip.
std::shared_ptr<const Scene> flat_surface(const Material& material, double gap) {
  auto scene = std::make_shared<Scene>(ultrasound_scene());
  Data data;
  forward_kinematics(Model(probe_settings().plant), data, kReady);
  scene->materials = {{"surface", material}};
  Box slab;
  slab.pose.translation = data.O_T_EE.translation - Vector3(0, 0, gap + 0.05);
  slab.half_size = Vector3(0.15, 0.15, 0.05);
  scene->obstacles = {Obstacle{"surface", "table", slab, {}, "surface", {}}};
  return scene;
}

Vector7 q_of(const rt::RobotState& s) { return Vector7(s.q.data()); }
Vector7 dq_of(const rt::RobotState& s) { return Vector7(s.dq.data()); }
Vector6 O_F_ext_of(const rt::RobotState& s) { return Vector6(s.O_F_ext_hat_K.data()); }

Matrix6x7 tcp_jacobian(const Model& model, const Vector7& q) {
  Data data;
  forward_kinematics(model, data, q);
  Matrix6x7 J;
  zero_jacobian(data, Frame::kEndEffector, J);
  return J;
}

Vector7 pushing_torque(const Emulator& emulator, const Vector3& force) {
  Data data;
  return pressing_torque(emulator.internal_model(), data, emulator.state(), force);
}

// Pushes with `force`, ramped in over the motion's first 0.5 s (libfranka's torque-rate limit).
void run_pushing(Emulator& emulator, const Vector3& force, int cycles) {
  if (!emulator.in_motion()) emulator.start_motion(ControlMode::kTorque);
  for (int k = 0; k < cycles && emulator.in_motion(); ++k) {
    const double ramp = std::min(1.0, static_cast<double>(emulator.counters().motion_cycles) / 500.0);
    const Command command{pushing_torque(emulator, ramp * force), false};
    emulator.step(&command);
  }
}

// Penetration of the probe into a flat surface at height z, from the robot's published kinematics
// and the tool's geometry (not from the contact engine).
double probe_depth(const Emulator& emulator, double surface_z) {
  const Eigen::Matrix4d O_T_EE = Eigen::Map<const Eigen::Matrix4d>(emulator.state().O_T_EE.data());
  const Transform& F_T_EE = ultrasound_scene().tool.F_T_EE;
  double lowest = std::numeric_limits<double>::infinity();
  for (const NamedCapsule& c : ultrasound_scene().tool.capsules)
    for (const Vector3& end : {c.capsule.a, c.capsule.b}) {
      const Vector3 in_ee = F_T_EE.rotation.transpose() * (end - F_T_EE.translation);
      lowest = std::min(lowest, (O_T_EE.topLeftCorner<3, 3>() * in_ee + O_T_EE.topRightCorner<3, 1>()).z() - c.capsule.radius);
    }
  return surface_z - lowest;
}

double surface_height(const Scene& scene) {
  const Box& slab = std::get<Box>(scene.obstacles[0].shape);
  return slab.pose.translation.z() + slab.half_size.z();
}

// Pressed with a known force F, the arm comes to rest where the surface pushes back with F: the
// indentation is the law's (F / k)^(1/n), measured from the arm's kinematics.
TEST(ContactEmulator, StaticIndentationIsTheLawsEquilibriumUnderAKnownForce) {
  for (const char* name : {"abdomen", "furniture"}) {
    const Material& m = shipped(name);
    rt::EmulatorSettings s = probe_settings();
    s.scene = flat_surface(m, 0.002);
    Emulator emulator(s);
    const double F = 10.0;
    run_pushing(emulator, Vector3(0, 0, -F), 4000);
    ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
    const double expected = std::pow(F / m.stiffness, 1.0 / m.exponent);
    EXPECT_NEAR(probe_depth(emulator, surface_height(*s.scene)), expected, 2e-3 * expected) << name;
    EXPECT_NEAR(emulator.contact().max_penetration, expected, 2e-3 * expected) << name;
    EXPECT_EQ(emulator.contact().active_contacts, 1);
    EXPECT_TRUE(near(emulator.contact().O_F_tool.head<3>(), Vector3(0, 0, -F), 5e-3 * F));   // the tilt mode still settling
    EXPECT_NEAR(emulator.contact().obstacle_normal_force[0], F, 5e-3 * F);
  }
}

// With the plant as its model, the robot's estimate of the wrench on K (= TCP) is the true one
// once the 30 Hz filter has settled; with another inertial set, it differs by what the model
// mismatch predicts at rest: (J J^T)^-1 J (g_plant - g_model) (tau_ext_hat attributes the
// unexplained gravity torque to the environment).
TEST(ContactEmulator, EstimatedContactWrenchMatchesTheTrueOneWithinTheModelMismatch) {
  const Material& m = shipped("abdomen");
  {
    rt::EmulatorSettings s = probe_settings();
    s.scene = flat_surface(m, 0.002);
    Emulator emulator(s);
    run_pushing(emulator, Vector3(3.0, 0, -12.0), 4000);
    ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
    EXPECT_TRUE(near(O_F_ext_of(emulator.state()), emulator.contact().O_F_tool, 0.02));
  }
  rt::EmulatorSettings s = probe_settings();
  ModelOptions o;
  o.inertia = "libfranka_fit";
  o.friction = "none";
  s.internal = with_tool(model_parameters(load_robot_config(robot_file("panda")), o), ultrasound_scene().tool);
  s.scene = flat_surface(m, 0.002);
  Emulator emulator(s);
  run_pushing(emulator, Vector3(3.0, 0, -12.0), 4000);
  ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  const Vector7 q = q_of(emulator.state());
  const Vector7 dg = gravity_of(emulator.plant_model(), q) - gravity_of(emulator.internal_model(), q);
  const Matrix6x7 J = tcp_jacobian(emulator.internal_model(), q);
  const Vector6 predicted = (J * J.transpose()).ldlt().solve(J * dg);
  const Vector6 error = O_F_ext_of(emulator.state()) - emulator.contact().O_F_tool;
  EXPECT_GT(predicted.head<3>().norm(), 0.05);   // the mismatch is visible ...
  EXPECT_TRUE(near(error.head<3>(), predicted.head<3>(), 0.05 * predicted.head<3>().norm() + 0.05));   // ... and explained
}


// ---------------------------------------------------------------------------------------------
// Impacts: the arm without gravity, thrown at the surface and then left alone (zero torque, no
// joint friction): a passive, conservative mechanism until it touches.

struct Throw {
  double v_in = 0.0, v_out = 0.0;          // the tip's normal speed before and after the first impact
  double max_penetration = 0.0;
  double kinetic_before = 0.0;             // when the push has ended
  double max_kinetic_apart = 0.0;          // the largest kinetic energy while nothing touches, after the first impact
  double max_free_flight_change = 0.0;     // |T - T_before| before the first impact: the integrator's own error
  bool finite = true;
  std::string reflex;
};

double kinetic_energy(const Emulator& emulator) {
  Data data;
  crba(emulator.plant_model(), data, q_of(emulator.state()));
  const Vector7 dq = dq_of(emulator.state());
  return 0.5 * dq.dot(data.mass_matrix * dq);
}

double tip_normal_velocity(const Emulator& emulator) {
  return (tcp_jacobian(emulator.plant_model(), q_of(emulator.state())) * dq_of(emulator.state()))[2];
}

// Pushes the TCP down with up to 5 N for 0.1 s (ramped within the torque-rate limit), then sends
// zero torque for `cycles`; the surface is far enough for the push to end before the impact.
Throw throw_at(const Material& material, double gap, int cycles) {
  rt::EmulatorSettings s = probe_settings(false);
  s.scene = flat_surface(material, gap);
  // The plant's physics, not the robot's reflexes (an impact on bone is above 100 N for a moment).
  for (Vector7* v : {&s.collision.upper_torque_acceleration, &s.collision.upper_torque_nominal}) v->setConstant(1e6);
  for (Vector6* v : {&s.collision.upper_force_acceleration, &s.collision.upper_force_nominal}) v->setConstant(1e6);
  Emulator emulator(s);
  emulator.start_motion(ControlMode::kTorque);
  Throw t;
  for (int k = 0; k < 100; ++k) {
    const double ramp = std::min({1.0, k / 40.0, (100 - k) / 40.0});
    const Command command{pushing_torque(emulator, Vector3(0, 0, -5.0 * ramp)) + 5.0 * dq_of(emulator.state()), false};
    emulator.step(&command);
  }
  const Command zero{Vector7::Zero(), false};
  for (int k = 0; k < 50; ++k) emulator.step(&zero);   // the torque loop's lag has died out
  EXPECT_EQ(emulator.contact().active_contacts, 0);
  t.kinetic_before = kinetic_energy(emulator);
  bool hit = false, separated = false;
  double previous_velocity = tip_normal_velocity(emulator);
  for (int k = 0; k < cycles && emulator.in_motion(); ++k) {
    emulator.step(&zero);
    const rt::ContactState& c = emulator.contact();
    const double T = kinetic_energy(emulator);
    t.finite = t.finite && std::isfinite(T);
    t.max_penetration = std::max(t.max_penetration, c.max_penetration);
    // The impact: a contact at the end of the cycle, or one that began and ended within it (a stiff
    // material's contact lasts less than a millisecond): the tip moves up.
    if (!hit && (c.active_contacts > 0 || tip_normal_velocity(emulator) > 0.0)) {
      hit = true;
      t.v_in = -previous_velocity;
    }
    if (!hit) t.max_free_flight_change = std::max(t.max_free_flight_change, std::abs(T - t.kinetic_before));
    if (hit && c.active_contacts == 0) {
      if (!separated) t.v_out = tip_normal_velocity(emulator);
      separated = true;
      t.max_kinetic_apart = std::max(t.max_kinetic_apart, T);
    }
    previous_velocity = tip_normal_velocity(emulator);
  }
  t.reflex = emulator.reflex_reason();
  return t;
}

// The first impact's rebound is Hunt-Crossley's for the impact speed (independent of the arm's
// effective mass), within what the arm's configuration change during the short contact allows.
// Without friction: the normal law alone.
TEST(ContactEmulator, DroppedToolReboundsWithHuntCrossleyRestitution) {
  for (const char* name : {"furniture", "thigh"}) {
    Material m = shipped(name);
    m.friction = 0.0;
    const Throw t = throw_at(m, 0.03, 800);
    ASSERT_GT(t.v_in, 0.05) << name;
    ASSERT_GT(t.v_out, 0.0) << name;
    const double e = t.v_out / t.v_in, expected = hunt_crossley_rebound_speed(m.damping, t.v_in) / t.v_in;
    EXPECT_NEAR(e, expected, 0.03) << name << ": impact at " << t.v_in << " m/s";
    EXPECT_LT(e, 1.0) << name;
  }
}

// Energy never grows in passive contact, and a stiffer material never makes the integration
// unstable at the shipped settings (the substep rule): over four decades of stiffness, from the
// abdomen to 100 times the skull's, the arm's kinetic energy whenever nothing touches stays at most
// its value before the impacts (plus the free flight's own integration error), and the deepest
// penetration stays within the 1-DOF energy bound k delta^(n+1)/(n+1) <= T_before.
TEST(ContactEmulator, EnergyNeverGrowsAndAStiffnessSweepStaysStable) {
  for (const double stiffness : {5.3e3, 1e5, 1e7, 7.9e8, 7.9e9, 7.9e10}) {
    const Material m{stiffness, 1.5, 0.5, 0.3};
    const Throw t = throw_at(m, 0.03, 800);
    ASSERT_TRUE(t.finite) << stiffness;
    EXPECT_EQ(t.reflex, "") << stiffness;
    ASSERT_GT(t.v_in, 0.05) << stiffness;
    EXPECT_LE(t.max_kinetic_apart, t.kinetic_before + 2.0 * t.max_free_flight_change + 1e-9) << stiffness;
    const double bound = std::pow((m.exponent + 1.0) * t.kinetic_before / m.stiffness, 1.0 / (m.exponent + 1.0));
    EXPECT_LE(t.max_penetration, bound) << stiffness;
  }
}


// Pressed with a known normal load and a tangential load below the friction cone, the probe creeps
// at the regularised law's speed v_s F_t / sqrt((mu F_n)^2 - F_t^2) for the applied loads: the
// implicit damping-and-friction step has the law's fixed point. It does so at the configured
// substeps: the friction's slope mu F_n / v_s (1500 N s/m here) needs no shorter step.
TEST(ContactEmulator, CreepBelowTheConeIsTheLawsSpeedForTheAppliedLoad) {
  const Material& m = shipped("abdomen");
  rt::EmulatorSettings s = probe_settings();
  s.scene = flat_surface(m, 0.002);
  Emulator emulator(s);
  const double normal = 10.0, tangential = 0.5 * m.friction * normal;
  run_pushing(emulator, Vector3(tangential, 0, -normal), 3000);
  ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  const double x0 = emulator.state().O_T_EE[12];
  run_pushing(emulator, Vector3(tangential, 0, -normal), 1000);
  const double creep = (emulator.state().O_T_EE[12] - x0) / 1.0;
  const double v_s = s.contact.friction_velocity;
  const double expected = v_s * tangential / std::sqrt(std::pow(m.friction * normal, 2) - tangential * tangential);
  // Measured 2.4 % fast: the load acts at the TCP, the contact lies on the probe's face below it,
  // and the arm turns a little under that moment (the controller holds no orientation).
  EXPECT_NEAR(creep, expected, 0.05 * expected);
  EXPECT_EQ(emulator.contact().active_contacts, 1);
  EXPECT_EQ(emulator.contact().substeps, s.substeps);
  EXPECT_LE(emulator.contact().newton_iterations, 3);
}

// The implicit step solves backward Euler: M (v - v_free) = h sum_c J_c^T F_c,dissipative(v), the
// dissipative forces being what the state reports at v (force minus the elastic k delta^n n); and
// with the surface at rest it never adds kinetic energy (v^T M v <= v_free^T M v_free: the
// minimiser of a convex dissipation potential smallest at rest). Random velocities, one pressing
// contact at a time from the flat surface under the probe and the furniture's stiff one.
TEST(ContactImplicitStep, SolvesBackwardEulerAndNeverAddsEnergy) {
  for (const char* name : {"abdomen", "furniture"}) {
    rt::EmulatorSettings s = probe_settings();
    s.scene = flat_surface(shipped(name), 0.002);
    Emulator emulator(s);
    run_pushing(emulator, Vector3(0, 0, -10.0), 1500);
    ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
    const Vector7 q = q_of(emulator.state());
    rt::SceneContact contact(s.scene, s.contact);
    rt::ContactState state = contact.initial_state();
    Data data;
    crba(emulator.plant_model(), data, q);
    const Matrix7 M = data.mass_matrix;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> speed(-0.05, 0.05);
    for (int trial = 0; trial < 20; ++trial) {
      Vector7 dq, v_free;
      for (int i = 0; i < kNumJoints; ++i) {
        dq[i] = speed(rng);
        v_free[i] = speed(rng);
      }
      contact.evaluate(emulator.plant_model(), data, 2.0, q, dq, state);
      ASSERT_EQ(state.active_contacts, 1) << name;
      const double h = 5e-4;
      const Vector7 v = contact.dissipate(data, M, dq, v_free, h, state);
      const rt::ContactPoint& c = state.contacts[0];
      const Vector3 dissipative = c.force - c.elastic_force * c.normal;
      const Vector7 residual = M * (v - v_free) - h * c.jacobian.transpose() * dissipative;
      EXPECT_LT(residual.norm(), 1e-10 * (1.0 + (M * v_free).norm())) << name << " trial " << trial;
      EXPECT_LE(v.dot(M * v), v_free.dot(M * v_free) * (1.0 + 1e-12)) << name << " trial " << trial;
      EXPECT_GE(c.normal_force, 0.0) << name;
      EXPECT_LE((c.force - c.force.dot(c.normal) * c.normal).norm(), c.friction_limit * (1.0 + 1e-12)) << name;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The robot around the contact: flags, reflexes, determinism

// A controller that pushes through the table gets the robot's reflex (libfranka's names), not a
// numerical explosion: the table holds (millimetres), the estimate crosses the user's thresholds.
TEST(ContactEmulator, PushingThroughTheTableTripsTheReflexNotAnExplosion) {
  rt::EmulatorSettings s = probe_settings();
  s.collision = rt::default_collision_behavior();   // libfranka's examples: 20 N accelerating, 10 N nominal
  s.scene = flat_surface(shipped("furniture"), 0.002);
  Emulator emulator(s);
  run_pushing(emulator, Vector3(0, 0, -200.0), 3000);
  EXPECT_FALSE(emulator.in_motion());
  const std::string reason = emulator.reflex_reason();
  EXPECT_NE(reason.find("reflex"), std::string::npos) << reason;   // cartesian_reflex and/or joint_reflex
  EXPECT_EQ(reason.find("diverged"), std::string::npos) << reason;
  EXPECT_TRUE(q_of(emulator.state()).allFinite());
  EXPECT_LT(emulator.contact().max_penetration, 1e-3);
  // The contact flags rose before the collision: a pressing force between the user's two levels
  // sets cartesian_contact and keeps the motion running.
  s.collision = probe_settings().collision;
  for (Vector6* v : {&s.collision.lower_force_acceleration, &s.collision.lower_force_nominal}) v->setConstant(5.0);
  Emulator pressing(s);
  run_pushing(pressing, Vector3(0, 0, -8.0), 1500);
  ASSERT_TRUE(pressing.in_motion()) << pressing.reflex_reason();
  EXPECT_EQ(pressing.state().cartesian_contact[2], 1.0);
  EXPECT_EQ(pressing.state().cartesian_collision[2], 0.0);
}

// Lockstep runs with contact (a moving, breathing surface, friction, adaptive substeps) are
// bit-for-bit reproducible.
TEST(ContactEmulator, LockstepRunsWithContactAreBitReproducible) {
  auto run = [] {
    rt::EmulatorSettings s = probe_settings();
    auto scene = std::make_shared<Scene>(*flat_surface(shipped("abdomen"), 0.002));
    scene->obstacles[0].motion = {Vector3(0, 0, 0.004), 0.25};
    s.scene = scene;
    Emulator emulator(s);
    std::vector<double> trace;
    emulator.start_motion(ControlMode::kTorque);
    for (int k = 0; k < 1500; ++k) {
      const Command command{pushing_torque(emulator, std::min(1.0, k / 500.0) * Vector3(2.0, 0, -8.0)), false};
      emulator.step(&command);
      for (double v : emulator.state().q) trace.push_back(v);
      for (double v : emulator.state().O_F_ext_hat_K) trace.push_back(v);
      trace.push_back(emulator.contact().max_penetration);
    }
    return trace;
  };
  const std::vector<double> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

// The breathing surface lifts the probe held by a constant force: the force stays (equilibrium of
// the law), the probe rides the surface up and down by the motion's amplitude.
TEST(ContactEmulator, ABreathingSurfaceCarriesTheProbeAtConstantForce) {
  rt::EmulatorSettings s = probe_settings();
  auto scene = std::make_shared<Scene>(*flat_surface(shipped("abdomen"), 0.002));
  scene->obstacles[0].motion = {Vector3(0, 0, 0.004), 0.25};
  s.scene = scene;
  Emulator emulator(s);
  run_pushing(emulator, Vector3(0, 0, -10.0), 1000);   // t = 1 s: the surface is up 4 mm
  ASSERT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  const double up = emulator.state().O_T_EE[14];
  run_pushing(emulator, Vector3(0, 0, -10.0), 2000);   // t = 3 s: down 4 mm
  const double down = emulator.state().O_T_EE[14];
  EXPECT_NEAR(up - down, 0.008, 0.001);
  EXPECT_NEAR(emulator.contact().obstacle_normal_force[0], 10.0, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Bad input

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = (temp_dir() / name).string();
  std::ofstream(path) << text;
  return path;
}

// The shipped ultrasound scene with one replacement in its text.
std::string edited_scene(const std::string& name, const std::string& from, const std::string& to) {
  std::ifstream in(scene_path("ultrasound_abdomen"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return write_file(name, text.replace(at, from.size(), to));
}

std::string config_error(const std::function<void()>& load) {
  try {
    load();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ContactBadInput, InvalidMaterialsNameTheFileAndKey) {
  const std::string negative = edited_scene("negative.yaml", "stiffness: 5300", "stiffness: -5300");
  std::string what = config_error([&] { load_scene(negative); });
  EXPECT_NE(what.find(negative), std::string::npos) << what;
  EXPECT_NE(what.find("materials.abdomen.stiffness"), std::string::npos) << what;
  const std::string nan = edited_scene("nan.yaml", "damping: 1.0", "damping: .nan");
  what = config_error([&] { load_scene(nan); });
  EXPECT_NE(what.find("materials.abdomen.damping: expected a finite number"), std::string::npos) << what;
  const std::string unknown = edited_scene("unknown.yaml", "material: abdomen", "material: liver");
  what = config_error([&] { load_scene(unknown); });
  EXPECT_NE(what.find("obstacles[4].material: expected the name of a material"), std::string::npos) << what;
  const std::string motion = edited_scene("motion.yaml", "frequency_hz: 0.25", "frequency_hz: -0.25");
  what = config_error([&] { load_scene(motion); });
  EXPECT_NE(what.find("obstacles[4].motion.frequency_hz: expected a positive number"), std::string::npos) << what;
  // Built in code: the emulator refuses it too.
  rt::EmulatorSettings s = probe_settings();
  auto scene = std::make_shared<Scene>(*flat_surface(shipped("abdomen"), 0.002));
  scene->materials["surface"].friction = -1.0;
  s.scene = scene;
  EXPECT_THROW(Emulator{s}, std::invalid_argument);
}

TEST(ContactBadInput, PenetrationAtTheStartNamesTheObstacleAndTheCapsule) {
  rt::EmulatorSettings s = probe_settings();
  s.scene = flat_surface(shipped("abdomen"), -0.01);   // the surface 1 cm above the probe's tip
  try {
    Emulator emulator(s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("capsule `probe` penetrates obstacle `surface`"), std::string::npos) << what;
  }
}

// A scenario naming a scene: its tool on the plant, the contact options, and the errors of each.
TEST(ContactBadInput, ScenarioSceneKeysAreCheckedAndMountTheTool) {
  const std::string head = "name: x\nrobot: " + robot_file("panda") +
                           "\nplant: {inertia: gaz2019}\ninitial_q: [0, -0.7853981633974483, 0, -2.356194490192345, 0, "
                           "1.5707963267948966, 0.7853981633974483]\nduration: 1\ncontroller: {type: float}\n";
  const rt::Scenario ok = rt::load_scenario(
      write_file("ok.yaml", head + "scene: " + scene_path("ultrasound_abdomen") + "\ncontact: {friction_velocity: 0.002}\n"));
  ASSERT_TRUE(ok.emulator.scene);
  EXPECT_EQ(ok.emulator.plant.end_effector.mass, ultrasound_scene().tool.inertia.mass);
  EXPECT_EQ(ok.emulator.internal.F_T_EE.translation, ultrasound_scene().tool.F_T_EE.translation);
  EXPECT_EQ(ok.emulator.contact.friction_velocity, 0.002);
  rt::Emulator emulator(ok.emulator);
  EXPECT_EQ(emulator.contact().active_contacts, 0);

  const std::string no_scene = write_file("no_scene.yaml", head + "contact: {max_substeps: 8}\n");
  EXPECT_NE(config_error([&] { rt::load_scenario(no_scene); }).find("contact: expected no contact options without a `scene`"),
            std::string::npos);
  const std::string hand = write_file("hand.yaml", head + "end_effector: hand\nscene: " + scene_path("ultrasound_abdomen") + "\n");
  EXPECT_NE(config_error([&] { rt::load_scenario(hand); }).find("end_effector: expected none"), std::string::npos);
  const std::string missing = write_file("missing.yaml", head + "scene: nowhere.yaml\n");
  EXPECT_NE(config_error([&] { rt::load_scenario(missing); }).find("scene: expected the path of a scene file"), std::string::npos);
  // A scene without its tool: the scene file's error, naming the key.
  std::ifstream in(scene_path("ultrasound_abdomen"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text = text.substr(0, text.find("tool:")) + text.substr(text.find("poses:"));
  const std::string toolless = write_file("toolless.yaml", text);
  const std::string what = config_error([&] { rt::load_scenario(write_file("toolless_scenario.yaml", head + "scene: " + toolless + "\n")); });
  EXPECT_NE(what.find(toolless + ": tool: expected this key (missing)"), std::string::npos) << what;
}

}  // namespace
}  // namespace csp::test
