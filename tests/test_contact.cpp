// Contact between the emulated arm and its scene (docs/contact.md), against physics: the force
// laws' closed forms (Hunt-Crossley's first integral, the regularised Coulomb law's creep speed),
// static equilibria of the whole plant, energy, the robot's estimate against the true wrench
// with the error its model mismatch predicts, reflexes as libfranka names them, bad input.
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>

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

const Scene& ultrasound_scene() {
  static const Scene scene = load_scene(scene_path("ultrasound_abdomen"));
  return scene;
}

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
  // libfranka's force_control example raises every threshold to 100 before it presses.
  rt::CollisionBehavior& c = s.collision;
  for (Vector7* v : {&c.lower_torque_acceleration, &c.upper_torque_acceleration, &c.lower_torque_nominal, &c.upper_torque_nominal})
    v->setConstant(100.0);
  for (Vector6* v : {&c.lower_force_acceleration, &c.upper_force_acceleration, &c.lower_force_nominal, &c.upper_force_nominal})
    v->setConstant(100.0);
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

// Torque that makes the TCP push with `force` (what the robot exerts on its environment), with
// joint damping: at rest, the TCP's wrench is exactly `force`.
Vector7 pushing_torque(const Emulator& emulator, const Vector3& force) {
  const Vector7 q = q_of(emulator.state()), dq = dq_of(emulator.state());
  Vector6 wrench = Vector6::Zero();
  wrench.head<3>() = force;
  return tcp_jacobian(emulator.internal_model(), q).transpose() * wrench - 5.0 * dq;
}

// Pushes with `force`, ramped in over the first 0.5 s (libfranka's torque-rate limit).
void run_pushing(Emulator& emulator, const Vector3& force, int cycles) {
  if (!emulator.in_motion()) emulator.start_motion(ControlMode::kTorque);
  for (int k = 0; k < cycles && emulator.in_motion(); ++k) {
    const Command command{pushing_torque(emulator, std::min(1.0, k / 500.0) * force), false};
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

}  // namespace
}  // namespace csp::test
