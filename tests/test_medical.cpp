// Issue 14's medical controllers, drilling and trocar laws, and scenarios (docs/medical.md):
// each law against an independent reference (finite differences of the kinematics, potential
// energy, closed-form steady states), and the shipped medical scenarios on the emulated robot.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "csp/planners/checker.hpp"
#include "csp/planners/task.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/medical_controllers.hpp"
#include "csp/rt/medical_metrics.hpp"
#include "csp/rt/medical_plant.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::rt {
namespace {

const std::string kMedical = std::string(CSP_SOURCE_DIR) + "/configs/scenarios/medical/";

Scenario medical_scenario(const std::string& name) { return load_scenario(kMedical + name + ".yaml"); }

// The base-frame rotation vector taking R0 to R1 (R1 = exp([w]) R0).
Vector3 rotation_vector(const Matrix3& R0, const Matrix3& R1) {
  const Eigen::AngleAxisd delta(R1 * R0.transpose());
  return delta.angle() * delta.axis();
}

// The joints that put the TCP at `position` with `rotation`, by resolved-rate steps from q.
Vector7 tcp_placed_at(const Model& model, Vector7 q, const Vector3& position, const Matrix3& rotation) {
  Data data;
  for (int k = 0; k < 200; ++k) {
    forward_kinematics(model, data, q);
    Matrix6x7 J;
    zero_jacobian(data, Frame::kEndEffector, J);
    const Transform& tcp = frame_pose(data, Frame::kEndEffector);
    Vector6 error;
    error << position - tcp.translation, rotation_vector(tcp.rotation, rotation);
    q += J.transpose() * (J * J.transpose()).ldlt().solve(error);
  }
  return q;
}

// --- The controllers' laws --------------------------------------------------------------------

// tau = J^T F + c: the torque's virtual work tau . dq equals F's on the TCP twist, the twist taken
// by central differences of the forward kinematics (not the library's Jacobian).
TEST(MedicalLaws, WrenchTorqueIsTheVirtualWorkOfTheWrench) {
  const Scenario scenario = medical_scenario("burr_hole_drilling");
  const Model model(scenario.emulator.internal);
  Data data;
  const Vector7 q = scenario.emulator.q_initial;
  forward_kinematics(model, data, q);
  Matrix6x7 jacobian;
  zero_jacobian(data, Frame::kEndEffector, jacobian);
  Vector6 wrench;
  wrench << 3.0, -2.0, 7.5, 0.4, -0.3, 0.2;
  const Vector7 coriolis = Vector7::LinSpaced(0.1, 0.7);
  const Vector7 tau = wrench_torque(jacobian, wrench, coriolis) - coriolis;
  const double h = 1e-6;
  for (int i = 0; i < kNumJoints; ++i) {
    Vector7 plus = q, minus = q;
    plus[i] += h;
    minus[i] -= h;
    forward_kinematics(model, data, plus);
    const Transform up = frame_pose(data, Frame::kEndEffector);
    forward_kinematics(model, data, minus);
    const Transform down = frame_pose(data, Frame::kEndEffector);
    const Vector3 v = (up.translation - down.translation) / (2.0 * h);
    const Vector3 w = rotation_vector(down.rotation, up.rotation) / (2.0 * h);
    EXPECT_NEAR(tau[i], wrench.head<3>().dot(v) + wrench.tail<3>().dot(w), 1e-6) << "joint " << i + 1;
  }
}

// libfranka's example error: position difference, and -R vec(q^-1 q_d) = -sin(theta/2) times the
// base-frame axis of the rotation from the pose to the desired orientation.
TEST(MedicalLaws, PoseErrorIsTheExampleQuaternionError) {
  Transform pose;
  pose.rotation = Eigen::AngleAxisd(0.7, Vector3(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  pose.translation = Vector3(0.4, -0.1, 0.3);
  const Vector3 local_axis = Vector3(0.3, -0.2, 0.9).normalized();
  const double theta = 0.25;
  const Eigen::Quaterniond desired(pose.rotation * Eigen::AngleAxisd(theta, local_axis).toRotationMatrix());
  const Vector6 e = pose_error(pose, Vector3(0.35, 0.0, 0.3), desired);
  EXPECT_TRUE(e.head<3>().isApprox(Vector3(0.05, -0.1, 0.0), 1e-12));
  EXPECT_TRUE(e.tail<3>().isApprox(-std::sin(theta / 2.0) * (pose.rotation * local_axis), 1e-9));
}

TEST(MedicalLaws, AxisSplitGainsActAlongAndNormalToTheAxis) {
  const Vector3 n = Vector3(1.0, -1.0, 2.0).normalized();
  const Matrix6 K = axis_split_gains(n, 2000.0, 300.0, 50.0);
  const Vector3 normal = n.unitOrthogonal();
  Vector6 along, across, turn;
  along << n, Vector3::Zero();
  across << normal, Vector3::Zero();
  turn << Vector3::Zero(), Vector3::UnitY();
  EXPECT_TRUE((K * along).isApprox(300.0 * along, 1e-12));
  EXPECT_TRUE((K * across).isApprox(2000.0 * across, 1e-12));
  EXPECT_TRUE((K * turn).isApprox(50.0 * turn, 1e-12));
  EXPECT_TRUE((critical_damping(n, 400.0, 100.0, 25.0) * along).isApprox(20.0 * along, 1e-12));
}

// The null-space torque exerts no wrench at the TCP: J of it is zero (the kinematic projector's
// definition), it leaves a torque that already exerts none unchanged, and removes any J^T F.
TEST(MedicalLaws, NullSpaceTorqueExertsNoWrenchAtTheTcp) {
  const Scenario scenario = medical_scenario("burr_hole_drilling");
  const Model model(scenario.emulator.internal);
  Data data;
  forward_kinematics(model, data, scenario.emulator.q_initial);
  Matrix6x7 J;
  zero_jacobian(data, Frame::kEndEffector, J);
  const Vector7 tau = Vector7::LinSpaced(-3.0, 4.0);
  const Vector7 projected = null_space_torque(J, tau);
  EXPECT_LT((J * projected).norm(), 1e-9 * tau.norm());
  EXPECT_TRUE(null_space_torque(J, projected).isApprox(projected, 1e-9));
  Vector6 wrench;
  wrench << 3.0, -2.0, 7.5, 0.4, -0.3, 0.2;
  EXPECT_LT(null_space_torque(J, J.transpose() * wrench).norm(), 1e-9);
}

TEST(MedicalLaws, LineOffsetIsTheShaftsDistanceFromThePivot) {
  const Vector3 axis = Vector3(0.0, 0.6, -0.8);
  const Vector3 pivot(0.5, 0.0, 0.25), normal(1.0, 0.0, 0.0);
  // A shaft through pivot + 3 mm along the normal, seen from two points on it.
  for (double s : {-0.1, 0.05}) {
    const Vector3 offset = line_offset_from(pivot + 0.003 * normal + s * axis, axis, pivot);
    EXPECT_TRUE(offset.isApprox(0.003 * normal, 1e-12));
  }
}

// On a static contact whose measured force is a fraction g of the command, the PI settles at the
// desired force (the integral takes up the rest); its integral stays inside the clamp.
TEST(MedicalLaws, ForcePISettlesOnTheDesiredForceAndClampsItsIntegral) {
  AxisForcePI pi(1.0, 2.0, 5.0);
  double command = 0.0;
  for (int k = 0; k < 20000; ++k) command = pi.update(8.0, 0.8 * command, 1e-3);
  EXPECT_NEAR(0.8 * command, 8.0, 1e-6);
  AxisForcePI free_space(1.0, 2.0, 5.0);
  for (int k = 0; k < 20000; ++k) command = free_space.update(8.0, 0.0, 1e-3);   // no contact: winds up
  EXPECT_DOUBLE_EQ(command, 8.0 + 8.0 + 5.0);
}

TEST(MedicalLaws, BreakthroughIsAThrustDropAfterEngagementOrAFeedJump) {
  BreakthroughDetector drop({8.0, 0.5, 4.0});
  EXPECT_FALSE(drop.update(3.0, 0.0, 0.001));    // approach: not engaged, a low thrust means nothing
  EXPECT_FALSE(drop.update(0.0, 0.0, 0.001));
  EXPECT_FALSE(drop.update(15.0, 0.001, 0.001)); // cutting
  EXPECT_FALSE(drop.update(7.6, 0.001, 0.001));  // above half the peak
  EXPECT_TRUE(drop.update(7.4, 0.001, 0.001));   // below it
  EXPECT_TRUE(drop.update(20.0, 0.0, 0.001));    // stays detected
  BreakthroughDetector jump({8.0, 0.5, 4.0});
  EXPECT_FALSE(jump.update(15.0, 0.0035, 0.001));
  EXPECT_TRUE(jump.update(15.0, 0.0041, 0.001));
}

// --- The drilling law ---------------------------------------------------------------------------

// Pushed at constant feed v, the bone's steady thrust is the inverse of the removal law,
// f = f_0 + v / c; breakthrough comes after T / v; over the last point height the thrust falls
// linearly; past the layer only the soft tissue pushes.
TEST(DrillingLaw, SteadyThrustBreakthroughTimeAndExit) {
  BoneLayerSettings settings;
  settings.dissipation = 0.0;
  BoneLayer bone(settings);
  const double v = 0.001, dt = 1e-4;
  double t = 0.0, thrust = 0.0, thrust_at_half = 0.0, thrust_in_exit = 0.0, removed_in_exit = 0.0;
  while (!bone.broken_through() && t < 20.0) {
    thrust = bone.step(v * t, v, dt);
    t += dt;
    if (std::abs(bone.removed() - 0.5 * settings.thickness) < 1e-6) thrust_at_half = thrust;
    const double left = settings.thickness - bone.removed();
    if (thrust_in_exit == 0.0 && left < 0.5 * settings.point_height) {
      thrust_in_exit = thrust;
      removed_in_exit = bone.removed();
    }
  }
  const double steady = settings.threshold_thrust + v / settings.removal_rate;   // 15 N
  EXPECT_NEAR(thrust_at_half, steady, 0.01 * steady);
  // The tip leads the face by f / k: breakthrough at (T + f / k) / v.
  EXPECT_NEAR(t, (settings.thickness + steady / settings.stiffness) / v, 0.01);
  EXPECT_NEAR(thrust_in_exit, steady * (settings.thickness - removed_in_exit) / settings.point_height, 0.02 * steady);
  const double soft = bone.step(settings.thickness + 0.002, v, dt);
  EXPECT_DOUBLE_EQ(soft, settings.soft_stiffness * 0.002);
}

TEST(DrillingLaw, NoThrustAboveTheBoneAndNoCutBelowTheThreshold) {
  BoneLayer bone(BoneLayerSettings{});
  EXPECT_EQ(bone.step(-0.001, 0.001, 1e-3), 0.0);
  const double f = bone.step(4.0 / 2.0e5, 0.0, 1.0);   // 4 N < f_0 = 5 N for a whole second
  EXPECT_NEAR(f, 4.0, 1e-9);
  EXPECT_EQ(bone.removed(), 0.0);
  EXPECT_EQ(bone.step(1e-5, -3.0, 1e-3), 0.0);   // withdrawing faster than 1 / alpha: Hunt-Crossley never pulls
}

TEST(DrillingLaw, BadNumbersAreRefused) {
  BoneLayerSettings bad;
  bad.thickness = -0.006;
  EXPECT_THROW(BoneLayer{bad}, std::invalid_argument);
  bad = BoneLayerSettings{};
  bad.removal_rate = std::nan("");
  EXPECT_THROW(BoneLayer{bad}, std::invalid_argument);
}

// The trocar ring's force at rest is the gradient of its potential U = k e^2 / 2 (e the shaft's
// offset in the wall): its generalised force J^T F is -dU/dq, by central differences in q.
TEST(TissueElement, TrocarForceIsThePotentialsGradient) {
  const Scenario scenario = medical_scenario("laparoscopic_pivoting");
  const TrocarSettings settings;
  TrocarRing trocar(*scenario.emulator.scene, settings);
  // A pose with the shaft through the wall, 4 mm off the trocar.
  const auto& pivot = std::get<RcmPivot>(scenario.emulator.scene->task);
  Model model(scenario.emulator.plant);
  Data data;
  Vector7 q = scenario.emulator.q_initial;
  forward_kinematics(model, data, q);
  const Matrix3 vertical = frame_pose(data, Frame::kEndEffector).rotation;   // the shaft along -z
  q = tcp_placed_at(model, q, pivot.trocar + Vector3(0.004, 0.0, -0.06), vertical);   // the tip 6 cm below, 4 mm aside
  forward_kinematics(model, data, q);
  const ToolForce f = trocar.force(0.0, data, Vector7::Zero());
  ASSERT_NEAR(trocar.offset(), 0.004, 1e-3);
  EXPECT_EQ(f.stiffness, settings.stiffness);
  const Vector7 tau = point_jacobian(data, kNumJoints, f.point).transpose() * f.force;
  const double k = settings.stiffness, h = 1e-6;
  auto potential = [&](const Vector7& at) {
    forward_kinematics(model, data, at);
    trocar.force(0.0, data, Vector7::Zero());
    return 0.5 * k * trocar.offset() * trocar.offset();
  };
  for (int i = 0; i < kNumJoints; ++i) {
    Vector7 plus = q, minus = q;
    plus[i] += h;
    minus[i] -= h;
    EXPECT_NEAR(tau[i], -(potential(plus) - potential(minus)) / (2.0 * h), 1e-5) << "joint " << i + 1;
  }
}

// A tissue element inside the contact engine: with the bit 0.1 mm into the skull at the burr
// entry, the bone layer's law pushes it back with k d = 20 N along the burr axis, the engine puts
// that force on the tool (O_F_tool) and on link 7 (its link wrench: RNEA's f_ext gives the joints
// -J^T F, the joint torque of that force), and leaves the skull to the element for the bit alone:
// without the element the same pose is the skull's rigid contact. An element naming no obstacle
// of the scene is refused, naming it.
TEST(TissueElement, TheEngineAppliesItsForceAndLeavesItsObstacleToIt) {
  const Scenario s = medical_scenario("burr_hole_drilling");
  const auto& hole = std::get<BurrHole>(s.emulator.scene->task);
  const Model model(s.emulator.plant);
  Data data;
  Vector7 q = s.emulator.q_initial;
  forward_kinematics(model, data, q);
  const Matrix3 aligned = frame_pose(data, Frame::kEndEffector).rotation;   // the bit along the burr axis
  q = tcp_placed_at(model, q, hole.entry - 1e-4 * hole.axis, aligned);   // the tip 0.1 mm below the entry
  const BoneLayerSettings settings;
  auto bone = std::make_shared<BoneUnderBurr>(*s.emulator.scene, settings);
  SceneContact engine(s.emulator.scene, s.emulator.contact, {{bone, "skull"}});
  ContactState state = engine.initial_state();
  engine.evaluate(model, data, 0.0, q, Vector7::Zero(), state);
  const Vector3 expected = settings.stiffness * 1e-4 * hole.axis;
  EXPECT_NEAR(bone->tip_depth(), 1e-4, 1e-9);
  EXPECT_LT((state.tissue[0].force - expected).norm(), 1e-6 * expected.norm());
  EXPECT_EQ(state.active_contacts, 0);   // the skull's rigid law does not touch the bit
  EXPECT_LT((state.O_F_tool.head<3>() + expected).norm(), 1e-9);
  Vector7 with_force, without;
  rnea(model, data, q, Vector7::Zero(), Vector7::Zero(), state.link_wrenches, with_force);
  rnea(model, data, q, Vector7::Zero(), Vector7::Zero(), without);
  forward_kinematics(model, data, q);
  Matrix6x7 J;
  zero_jacobian(data, Frame::kEndEffector, J);
  EXPECT_LT((without - with_force - J.topRows<3>().transpose() * expected).norm(), 1e-9);

  SceneContact rigid(s.emulator.scene, s.emulator.contact);
  ContactState rigid_state = rigid.initial_state();
  rigid.evaluate(model, data, 0.0, q, Vector7::Zero(), rigid_state);
  ASSERT_GE(rigid_state.active_contacts, 1);
  EXPECT_EQ(s.emulator.scene->obstacles[rigid_state.contacts[0].obstacle].name, "skull");

  try {
    SceneContact wrong(s.emulator.scene, s.emulator.contact, {{bone, "skul"}});
    ADD_FAILURE() << "an element naming no obstacle was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no obstacle `skul`"), std::string::npos) << e.what();
  }
}

// --- The scenarios ------------------------------------------------------------------------------

struct MedicalRun {
  MotionResult result;
  std::vector<MedicalMetric> metrics;
  RobotState last;       // the last published state (a reflex's)
  double last_t = 0.0;   // its motion time [s]
  double metric(const std::string& name) const {
    for (const MedicalMetric& m : metrics)
      if (m.name == name) return m.value;
    ADD_FAILURE() << "no metric " << name;
    return NAN;
  }
};

// The scenario on the emulator with its metrics; `watch` sees each published state at motion time t.
MedicalRun run(const Scenario& scenario, const std::function<void(const RobotState&, double t)>& watch = {}) {
  Emulator emulator(scenario.emulator);
  const BuiltinController builtin = make_controller(scenario.controller, scenario.controller_faults, emulator);
  MedicalRecorder recorder(scenario, emulator, builtin.status);
  const uint64_t start_ms = emulator.state().time.toMSec();
  LoopOptions options;
  options.max_duration = scenario.duration;
  MedicalRun r;
  options.observer = [&](const RobotState& state, const CycleInfo&) {
    r.last = state;
    r.last_t = static_cast<double>(state.time.toMSec() - start_ms) * 1e-3;
    recorder.add(state, r.last_t);
    if (watch) watch(state, r.last_t);
  };
  r.result = run_motion(emulator, builtin.mode, builtin.controller, options);
  r.metrics = recorder.metrics();
  return r;
}

// setCollisionBehavior's force thresholds (contact `lower`, collision `upper`, N) below what the
// scenario needs end it in libfranka's cartesian_reflex, tripped by the force along the tool's axis
// (K's z: the probe's or the drill's push on the tissue), not by another component of the estimate.
void expect_cartesian_reflex(Scenario s, double lower, double upper) {
  CollisionBehavior& c = s.emulator.collision;
  c.lower_force_acceleration = c.lower_force_nominal = Vector6::Constant(lower);
  c.upper_force_acceleration = c.upper_force_nominal = Vector6::Constant(upper);
  const MedicalRun r = run(s);
  EXPECT_TRUE(r.result.reflex);
  EXPECT_TRUE(r.result.errors.has(Error::cartesian_reflex)) << std::string(r.result.errors);
  EXPECT_GT(std::abs(r.last.K_F_ext_hat_K[2]), upper);
}

// Drilling with breakthrough detection stops within 1.5 mm past the bone, or before it with less
// than the point's height (1.05 mm) of bone left (docs/medical.md); without it the feed runs on
// through the layer to the task's advance, 4 mm past the 6 mm layer.
TEST(MedicalScenarios, DrillingStopsAtBreakthroughOnlyWithDetection) {
  Scenario on = medical_scenario("burr_hole_drilling");
  const MedicalRun detected = run(on);
  ASSERT_FALSE(detected.result.reflex) << detected.result.reason;
  EXPECT_TRUE(std::isfinite(detected.metric("breakthrough detected at")));
  EXPECT_LT(detected.metric("overshoot past the bone"), 1.5);
  EXPECT_LT(detected.metric("bone left under the bit"), 1.05);
  EXPECT_GT(detected.metric("thrust max"), 10.0);

  Scenario off = medical_scenario("burr_hole_drilling");
  off.controller.medical.breakthrough_detection = false;
  const MedicalRun blind = run(off);
  ASSERT_FALSE(blind.result.reflex) << blind.result.reason;
  EXPECT_TRUE(std::isnan(blind.metric("breakthrough detected at")));
  EXPECT_TRUE(std::isfinite(blind.metric("breakthrough time")));
  EXPECT_GT(blind.metric("overshoot past the bone"), 3.0);
}

// The scans at 8 N on the breathing abdomen and on the thigh: within 1.5 N RMS of the commanded force, no contact
// lost, the path within 2 mm; a Cartesian force threshold below the 8 N it needs: cartesian_reflex, on the
// contact force along the probe (measured: the probe reaches the skin at 2.11 s, the reflex trips at 2.36 s
// with 5.0 N along K's z; before the contact the estimate stays below 1.2 N, under the 3 N contact level).
TEST(MedicalScenarios, UltrasoundScanHoldsItsForceAndTripsBelowIt) {
  for (const char* name : {"ultrasound_abdomen_scan", "doppler_thigh_scan"}) {
    Scenario s = medical_scenario(name);
    s.duration = 7.0;
    const MedicalRun nominal = run(s);
    ASSERT_FALSE(nominal.result.reflex) << name << ": " << nominal.result.reason;
    EXPECT_LT(nominal.metric("contact force RMS error (scan)"), 1.5) << name;
    EXPECT_EQ(nominal.metric("contact losses"), 0.0) << name;
    EXPECT_LT(nominal.metric("path error max (scan)"), 2.0) << name;
  }

  Scenario low = medical_scenario("ultrasound_abdomen_scan");
  low.duration = 7.0;
  expect_cartesian_reflex(low, 3.0, 5.0);
}

// How a scan followed its planned path q_p, over the scan (motion time >= settle): the TCP's largest
// distance from FK(q_p) normal to the probe axis (along it the force rules: the probe is pressed
// into the skin the path lies on); the largest self-motion away from q_p, the null-space part
// (1 - J^+ J)(q - q_p) (what the Cartesian impedance leaves free); every 0.1 s, the least clearance
// of the arm and of q_p by the planner's own checker in the task's contact scene (planners/task.hpp:
// the links keep the patient's clearance, the tool may touch, the probe's tip is exempt from the skin).
struct PathFollowing {
  MedicalRun run;
  double lateral_max = 0.0;   // [m]
  double posture_max = 0.0;   // [rad]
  double clearance_min = INFINITY, planned_clearance_min = INFINITY;   // [m]
};

PathFollowing follow_path(const Scenario& s) {
  const MedicalControllerSpec& m = s.controller.medical;
  const Scene& scene = *s.emulator.scene;
  const Model model(s.emulator.plant);
  Data data;
  const Vector3 n = std::get<UltrasoundScan>(scene.task).tool_axis.normalized();
  planners::TaskConstraint task(model, scene);
  planners::ClearanceChecker checker(model, planners::contact_scene(scene, task.contact_obstacle()));
  PathFollowing f;
  f.run = run(s, [&](const RobotState& state, double t) {
    if (t < m.settle) return;
    Vector7 q_p, dq_p, ddq_p;
    m.path->evaluate(Vector7::Zero(), t - m.settle, q_p, dq_p, ddq_p);
    forward_kinematics(model, data, q_p);
    const Vector3 planned = frame_pose(data, Frame::kEndEffector).translation;
    const Vector7 q(state.q.data());
    forward_kinematics(model, data, q);
    const Vector3 d = frame_pose(data, Frame::kEndEffector).translation - planned;
    f.lateral_max = std::max(f.lateral_max, (d - n.dot(d) * n).norm());
    Matrix6x7 J;
    zero_jacobian(data, Frame::kEndEffector, J);
    // The kinematic projector is symmetric: 1 - J^T (J J^T)^-1 J = 1 - J^+ J, on a joint step too.
    f.posture_max = std::max(f.posture_max, null_space_torque(J, q - q_p).norm());
    if (std::lround(t * 1e3) % 100 == 0) {
      f.clearance_min = std::min(f.clearance_min, checker.check(q).clearance);
      f.planned_clearance_min = std::min(f.planned_clearance_min, checker.check(q_p).clearance);
    }
  });
  return f;
}

// The scans along the planner's task paths (configs/scenarios/medical/plans), whole:
// - the force held within 1.5 N RMS, no contact lost;
// - the TCP within 3 mm of FK(q_p) normal to the probe axis (measured 1.7 / 2.1 mm: a lag along the
//   scan of 1.5-1.9 mm, of which the skin's Coulomb friction mu F_d / k_t = 0.15 * 8 / 2000 = 0.6 mm,
//   the rest the joints' friction the law does not compensate; across it 0.8 / 1.1 mm);
// - the self-motion within twice the joints' stiction band |tau_breakaway| / k_n (0.012 rad at
//   k_n = 50: a joint at rest holds up to its breakaway torque against the null-space spring; the
//   projector couples the joints, so the band is a scale, not a bound: measured 1.1 / 1.7 band, the
//   thigh's stick-slip changing with the reference's last digits (1.0 band on the 1 kHz rows, 1.7 on
//   the shipped 100 Hz ones, 3e-6 rad apart)); without the null-space term nothing pulls the hover
//   pose's self-motion to the planned posture (measured 0.11 / 0.27 rad, 8 / 12 times more);
// - the clearance the planner checked, less what the contact takes: the arm is the plan pushed into
//   the skin by the indentation (8 N: 13 mm on the abdomen, 7 mm on the thigh), the breathing (4 mm)
//   and the lateral error, so at most 20 mm less (measured 0.057 against the plan's 0.075 m, the
//   probe holder over the abdomen; 0.039 against 0.040 m on the thigh).
TEST(MedicalScenarios, ScansFollowThePlannedPathAndItsPosture) {
  for (const char* name : {"ultrasound_abdomen_scan", "doppler_thigh_scan"}) {
    Scenario s = medical_scenario(name);
    ASSERT_TRUE(s.controller.medical.path) << name;
    const PathFollowing held = follow_path(s);
    ASSERT_FALSE(held.run.result.reflex) << name << ": " << held.run.result.reason;
    EXPECT_LT(held.run.metric("contact force RMS error (scan)"), 1.5) << name;
    EXPECT_EQ(held.run.metric("contact losses"), 0.0) << name;
    EXPECT_LT(held.lateral_max, 3e-3) << name;
    const double stiction_band = s.emulator.plant.friction.breakaway.norm() / s.controller.medical.null_space_stiffness;
    EXPECT_LT(held.posture_max, 2.0 * stiction_band) << name;
    EXPECT_GT(held.clearance_min, 0.0) << name;
    EXPECT_GT(held.clearance_min, held.planned_clearance_min - 0.02) << name;

    s.controller.medical.null_space_stiffness = 0.0;
    const PathFollowing drifting = follow_path(s);
    ASSERT_FALSE(drifting.run.result.reflex) << name << ": " << drifting.run.result.reason;
    EXPECT_GT(drifting.posture_max, 5.0 * held.posture_max) << name;
  }
}

// A collision threshold on the Cartesian force below the drill's thrust: libfranka's cartesian_reflex
// (measured at 7.61 s, on the thrust along the bit).
TEST(MedicalScenarios, DrillingThrustAboveTheForceThresholdIsACartesianReflex) {
  expect_cartesian_reflex(medical_scenario("burr_hole_drilling"), 5.0, 8.0);
}

TEST(MedicalScenarios, PivotingKeepsTheRemoteCentreOfMotion) {
  Scenario s = medical_scenario("laparoscopic_pivoting");
  s.duration = 6.0;
  const MedicalRun r = run(s);
  ASSERT_FALSE(r.result.reflex) << r.result.reason;
  EXPECT_LT(r.metric("RCM deviation max"), 3.0);
  // The ring's force is its stiffness times the deviation.
  EXPECT_NEAR(r.metric("trocar force max"), 1000.0 * 1e-3 * r.metric("RCM deviation max"), 1.0);
}

// The pivot's own estimated external torques (the trocar ring on the shaft, the swinging arm's model
// mismatch), measured on the nominal run: the peak |tau_ext_hat_filtered| per joint during the
// insertion and during the pivot. (The estimate starts at zero and grows with the insertion's motion:
// there is no start transient above the insertion's own values to leave out.) Thresholds 10 % below
// the pivot's peak, on the joints where that still exceeds the insertion's peak (measured: joints 1,
// 2, 3, 5, 7; the others keep the nominal thresholds), trip joint_reflex during the pivot (measured
// at 3.49 s, the insertion ends at 3 s); the nominal thresholds do not trip.
TEST(MedicalScenarios, PivotingAboveItsOwnTorqueThresholdsIsAJointReflex) {
  constexpr double kBelowPeak = 0.9;
  Scenario s = medical_scenario("laparoscopic_pivoting");
  s.duration = 6.0;
  const double pivot_start = s.controller.medical.insertion_time;
  Vector7 before = Vector7::Zero(), during = Vector7::Zero();
  const MedicalRun nominal = run(s, [&](const RobotState& state, double t) {
    Vector7& peak = t < pivot_start ? before : during;
    peak = peak.cwiseMax(Vector7(state.tau_ext_hat_filtered.data()).cwiseAbs());
  });
  ASSERT_FALSE(nominal.result.reflex) << nominal.result.reason;

  CollisionBehavior& c = s.emulator.collision;
  int lowered = 0;
  for (int i = 0; i < kNumJoints; ++i) {
    const double threshold = kBelowPeak * during[i];
    if (threshold <= before[i]) continue;
    c.lower_torque_acceleration[i] = c.lower_torque_nominal[i] = threshold;
    c.upper_torque_acceleration[i] = c.upper_torque_nominal[i] = threshold;
    ++lowered;
  }
  ASSERT_GT(lowered, 0) << "no joint whose pivot torque exceeds its insertion torque";
  const MedicalRun r = run(s);
  ASSERT_TRUE(r.result.reflex);
  EXPECT_TRUE(r.result.errors.has(Error::joint_reflex)) << std::string(r.result.errors);
  EXPECT_GT(r.last_t, pivot_start);
}

// --- Bad input -----------------------------------------------------------------------------------

// A shipped medical scenario with `from` replaced by `to`, written where the test may write (its
// relative paths made absolute); the error load_scenario gives, or "" if it loads.
std::string load_error(const std::string& name, const std::string& from, const std::string& to) {
  std::ifstream in(kMedical + name + ".yaml");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  for (auto at = text.find("path: plans/"); at != std::string::npos; at = text.find("path: plans/", at + 1))
    text.replace(at + 6, 0, kMedical);
  for (const char* dir : {"robots", "scenes"}) {
    const std::string relative = std::string("../../") + dir, absolute = std::string(CSP_SOURCE_DIR) + "/configs/" + dir;
    for (auto at = text.find(relative); at != std::string::npos; at = text.find(relative)) text.replace(at, relative.size(), absolute);
  }
  const std::string path = testing::TempDir() + "/medical_" + name + ".yaml";
  std::ofstream(path) << text;
  try {
    load_scenario(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(MedicalBadInput, EachMistakeNamesItsKey) {
  EXPECT_EQ(load_error("burr_hole_drilling", "thickness: 0.006", "thickness: 0.006"), "");
  EXPECT_NE(load_error("burr_hole_drilling", "obstacle: skull", "obstacle: skul").find("tissue.bone.obstacle: expected the name of an obstacle"),
            std::string::npos);
  EXPECT_NE(load_error("burr_hole_drilling", "thickness: 0.006", "thickness: -0.006").find("tissue.bone.thickness: expected a positive number"),
            std::string::npos);
  EXPECT_NE(load_error("burr_hole_drilling", "bone: {obstacle: skull, thickness: 0.006}", "trocar: {obstacle: skull}").find("a trocar needs a scene whose task is an rcm_pivot"),
            std::string::npos);
  EXPECT_NE(load_error("laparoscopic_pivoting", "insertion: 0.06", "feed_rate: 0.001").find("controller.feed_rate: expected no `feed_rate` for a rcm controller"),
            std::string::npos);
  EXPECT_NE(load_error("ultrasound_abdomen_scan", "scene: ../../scenes/ultrasound_abdomen.yaml\n", "").find("a scene (`scene:`) for a cartesian_impedance_force controller"),
            std::string::npos);
  const std::string plan = "path: plans/ultrasound_abdomen/trajectory.csv";
  EXPECT_NE(load_error("ultrasound_abdomen_scan", plan, "path: plans/ultrasound_abdomen/no_such.csv")
                .find("ultrasound_abdomen_scan.yaml: controller.path: expected a joint log (docs/joint-log.md), relative to this scenario"),
            std::string::npos);
  EXPECT_NE(load_error("ultrasound_abdomen_scan", plan, "path: plans/doppler_femoral/trajectory.csv")
                .find("controller.path: expected a path whose first pose is the scan's start"),
            std::string::npos);
  EXPECT_NE(load_error("ultrasound_abdomen_scan", "  " + plan + "\n", "")
                .find("controller.null_space_stiffness: expected a `path` too"),
            std::string::npos);
  EXPECT_NE(load_error("laparoscopic_pivoting", "insertion: 0.06", "path: plans/ultrasound_abdomen/trajectory.csv")
                .find("controller.path: expected no `path` for a rcm controller"),
            std::string::npos);
}

}  // namespace
}  // namespace csp::rt
