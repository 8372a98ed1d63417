// The emulated robot's Cartesian motion generators, its inverse kinematics, its Cartesian impedance
// controller and torque control next to a motion generator, against independent references: KDL's
// forward kinematics, the arm's geometry (the elbow flip), analytic integrals of libfranka's
// example motions, Hooke's law, and one purpose-built command per error flag.
#include <cmath>
#include <cstring>
#include <functional>

#include "csp/dynamics/arrays.hpp"
#include "csp/rt/cartesian_motion.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/scenario.hpp"
#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using rt::Command;
using rt::ControllerMode;
using rt::ControlMode;
using rt::Emulator;
using rt::Error;

constexpr double kDt = rt::kDeltaT;

// libfranka's examples' start configuration (examples_common: move to this q first).
const Vector7 kStart = (Vector7() << 0.0, -M_PI_4, 0.0, -3.0 * M_PI_4, 0.0, M_PI_2, M_PI_4).finished();

// The Panda with the hand, plant == the robot's model, no friction, no scripted wrench.
rt::EmulatorSettings panda(const Vector7& q = kStart) {
  rt::EmulatorSettings s = rt::load_scenario(rt::default_scenario_path()).emulator;
  ModelOptions o;
  o.end_effector = "hand";
  o.friction = "none";
  s.plant = s.internal = model_parameters(load_robot_config(robot_file("panda")), o);
  s.external_wrenches.clear();
  s.q_initial = q;
  return s;
}

Transform pose_of(const std::array<double, 16>& a) { return transform_from_array(a); }
double position_distance(const Transform& a, const Transform& b) { return (a.translation - b.translation).norm(); }
double rotation_distance(const Transform& a, const Transform& b) {
  return rt::rotation_log(a.rotation * b.rotation.transpose()).norm();
}

Command pose_command(const Transform& pose) {
  Command c;
  c.O_T_EE_c = to_array(pose);
  return c;
}
Command twist_command(const Vector6& twist) {
  Command c;
  c.O_dP_EE_c = to_array(twist);
  return c;
}

// The only flag of `errors`: each purpose-built command must trip its error and nothing else.
void expect_only(const rt::ErrorSet& errors, Error error) {
  EXPECT_TRUE(errors.has(error)) << rt::error_name(error) << " expected, got " << std::string(errors);
  rt::ErrorSet only;
  only.set(error);
  EXPECT_EQ(errors, only) << std::string(errors);
}

// ---------------------------------------------------------------------------------------------
// Kinematics

// kElbowFlip (libfranka's number) is where the arm is stretched: the distance from the shoulder
// (joint 2's origin) to the wrist (joint 5's axis point, frame 5's origin) is largest there.
TEST(EmulatorCartesian, ElbowFlipIsTheStretchedArm) {
  const Model model = make_model("panda");
  Data data;
  const auto reach = [&](double q4) {
    Vector7 q = kStart;
    q[3] = q4;
    forward_kinematics(model, data, q);
    return (data.O_T_joint[4].translation - data.O_T_joint[1].translation).norm();
  };
  // Golden-section search for the maximum of reach(q4) on [-1.5, 0].
  double a = -1.5, b = 0.0;
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  while (b - a > 1e-9) {
    const double c = b - r * (b - a), d = a + r * (b - a);
    if (reach(c) > reach(d)) b = d;
    else a = c;
  }
  EXPECT_NEAR(0.5 * (a + b), rt::kElbowFlip, 1e-6);
  EXPECT_EQ(rt::elbow_sign(-0.3), 1.0);
  EXPECT_EQ(rt::elbow_sign(-2.0), -1.0);
  EXPECT_EQ(rt::elbow_sign(rt::kElbowFlip), 0.0);
}

// Inverse kinematics round trip: the pose of random joints by KDL's forward kinematics, solved
// from a start 0.05 rad away with q3 given, gives back the joints (the solution is locally
// unique) and, by KDL again, the pose.
TEST(EmulatorCartesian, InverseKinematicsRoundTripAgainstKdl) {
  ModelOptions options;
  options.end_effector = "hand";
  const Model model = make_model("panda", options);
  KdlPeer kdl(model);
  Data data;
  RandomStates random(7);
  JointLimits inner = model.parameters().joint_limits;
  inner.q_min.array() += 0.3;   // away from the limits and from the stretched elbow
  inner.q_max.array() -= 0.3;
  inner.q_max[3] = rt::kElbowFlip - 0.3;
  int solved = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vector7 q = random.q(inner);
    const Transform target = kdl.ee_pose(q);
    Matrix6x7 J = kdl.ee_jacobian(q);
    Matrix6 J6;
    for (int c = 0, j = 0; j < kNumJoints; ++j)
      if (j != 2) J6.col(c++) = J.col(j);
    if (J6.jacobiSvd().singularValues().minCoeff() < 0.05) continue;   // near a singularity: not locally unique
    ++solved;
    const Vector7 start = q + 0.05 * Vector7::Random();
    const rt::InverseKinematics ik = rt::inverse_kinematics(model, data, target, q[2], start);
    ASSERT_TRUE(ik.converged) << "trial " << trial << ": left " << ik.position_error << " m";
    EXPECT_LT((ik.q - q).cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
    EXPECT_EQ(ik.q[2], q[2]);
    EXPECT_LT(position_distance(kdl.ee_pose(ik.q), target), 1e-9);
    EXPECT_LT(rotation_distance(kdl.ee_pose(ik.q), target), 1e-9);
    EXPECT_LE(ik.iterations, 6);
  }
  EXPECT_GT(solved, 100);
}

TEST(EmulatorCartesian, HomogeneousPoseCheck) {
  Transform t;
  t.rotation = rt::rotation_exp(Vector3(0.3, -0.2, 1.0));
  t.translation << 0.4, 0.1, 0.5;
  EXPECT_EQ(rt::homogeneous_pose_problem(to_array(t)), "");
  std::array<double, 16> a = to_array(t);
  a[0] *= 1.0001;   // a column of norm 1.0001: beyond libfranka's 1e-5
  EXPECT_NE(rt::homogeneous_pose_problem(a), "");
  a = to_array(t);
  a[3] = 1e-3;      // bottom row
  EXPECT_NE(rt::homogeneous_pose_problem(a), "");
  a = to_array(t);
  for (int i : {0, 1, 2}) a[i] = -a[i];   // a reflection: unit rows and columns, determinant -1
  EXPECT_NE(rt::homogeneous_pose_problem(a), "");
}

// ---------------------------------------------------------------------------------------------
// Motions

// libfranka's generate_cartesian_pose_motion: a quarter circle of 0.3 m in the x-z plane in 10 s,
// from the measured pose. The measured EE follows within 1 mm (the joint impedance's error
// ~ |M ddq + c| / K: about 0.12 m/s^2 of EE acceleration, 3000 N m/rad, gives tenths of a mm);
// the robot's commanded pose is the one sent and its desired pose (FK of q_c) reaches it.
void run_circle(ControllerMode controller, double bound) {
  Emulator emulator(panda());
  emulator.start_motion(ControlMode::kCartesianPose, controller);
  const Transform initial = pose_of(emulator.state().O_T_EE);
  const double q3 = emulator.state().q[2];
  double worst = 0.0, worst_desired = 0.0;
  for (int k = 0; k <= 10000; ++k) {
    const double t = k * kDt;
    const double angle = M_PI / 4.0 * (1.0 - std::cos(M_PI / 5.0 * t));
    Transform pose = initial;
    pose.translation.x() += 0.3 * std::sin(angle);
    pose.translation.z() += 0.3 * (std::cos(angle) - 1.0);
    Command command = pose_command(pose);
    command.motion_finished = k == 10000;
    emulator.step(&command);
    const rt::RobotState& s = emulator.state();
    ASSERT_EQ(s.robot_mode, k == 10000 ? rt::RobotMode::kIdle : rt::RobotMode::kMove) << emulator.reflex_reason();
    // The last command ends the motion: Idle then desires where the arm is (docs/franka_api.md).
    if (k < 10000) {
      EXPECT_EQ(s.O_T_EE_c, command.O_T_EE_c);
      worst_desired = std::max(worst_desired, position_distance(pose_of(s.O_T_EE_d), pose));
    }
    worst = std::max(worst, position_distance(pose_of(s.O_T_EE), pose));
    EXPECT_LT(std::abs(s.q[2] - q3), 1e-3);   // the elbow stays
  }
  std::printf("circle (%s): EE within %.3g mm of the command, desired within %.3g m\n",
              rt::controller_mode_name(controller), worst * 1e3, worst_desired);
  EXPECT_LT(worst, bound);
  EXPECT_LT(worst_desired, 1e-9);
}

TEST(EmulatorCartesian, CircleTrackedWithJointImpedance) { run_circle(ControllerMode::kJointImpedance, 1e-3); }

// The Cartesian impedance (3000 N/m): the force for ~0.12 m/s^2 on a few kg of Cartesian inertia
// is ~1 N, a third of a mm at 3000 N/m; 2 mm bound.
TEST(EmulatorCartesian, CircleTrackedWithCartesianImpedance) { run_circle(ControllerMode::kCartesianImpedance, 2e-3); }

// libfranka's generate_cartesian_velocity_motion (v_max 0.1 m/s, 45 degrees down in x-z, T = 4 s
// out and back) plus a rotation about z: the commanded pose is the integral of the commanded twist.
// Analytic: s(t) = v_max/2 (t - T/(2 pi) sin(2 pi t/T)) per half; the 1 ms sum of the robot
// differs from the integral by at most dt max|v|.
TEST(EmulatorCartesian, VelocityModeIntegratesToTheAnalyticPose) {
  Emulator emulator(panda());
  emulator.start_motion(ControlMode::kCartesianVelocity);
  const Transform initial = pose_of(emulator.state().O_T_EE_c);
  const double v_max = 0.1, T = 4.0, angle = M_PI / 4.0, w_max = 0.2;
  const auto speed = [&](double t) { return (t < T ? 1.0 : -1.0) * v_max / 2.0 * (1.0 - std::cos(2.0 * M_PI / T * t)); };
  const auto distance = [&](double t) {
    const double s = v_max / 2.0 * (std::min(t, T) - T / (2.0 * M_PI) * std::sin(2.0 * M_PI / T * std::min(t, T)));
    return t < T ? s : s - v_max / 2.0 * ((t - T) - T / (2.0 * M_PI) * std::sin(2.0 * M_PI / T * (t - T)));
  };
  double worst_position = 0.0, worst_rotation = 0.0;
  const int cycles = static_cast<int>(2 * T / kDt);
  for (int k = 1; k <= cycles; ++k) {
    const double t = k * kDt;
    const double v = speed(t);
    Command command = twist_command((Vector6() << std::cos(angle) * v, 0, -std::sin(angle) * v, 0, 0, w_max / v_max * v).finished());
    command.motion_finished = k == cycles;
    emulator.step(&command);
    const rt::RobotState& s = emulator.state();
    if (k == cycles) break;
    ASSERT_EQ(s.robot_mode, rt::RobotMode::kMove) << emulator.reflex_reason();
    Transform expected = initial;
    expected.translation += distance(t) * Vector3(std::cos(angle), 0.0, -std::sin(angle));
    expected.rotation = rt::rotation_exp(Vector3(0, 0, w_max / v_max * distance(t))) * initial.rotation;
    worst_position = std::max(worst_position, position_distance(pose_of(s.O_T_EE_c), expected));
    worst_rotation = std::max(worst_rotation, rotation_distance(pose_of(s.O_T_EE_c), expected));
    EXPECT_LT(position_distance(pose_of(s.O_T_EE_d), pose_of(s.O_T_EE_c)), 1e-9);
    EXPECT_NEAR(s.O_dP_EE_c[0], std::cos(angle) * v, 1e-12);
  }
  EXPECT_LT(worst_position, kDt * v_max);
  EXPECT_LT(worst_rotation, kDt * w_max);
  EXPECT_LT(distance(2 * T), 1e-12);   // out and back
}

// libfranka's generate_elbow_motion: the pose held, the elbow (joint 3) moved by
// pi/10 (1 - cos(pi t/5)) over 10 s. Joint 3 follows the elbow exactly in q_c, the desired pose
// stays the initial one, the measured EE moves less than a mm while joint 3 turns by pi/5 and back.
TEST(EmulatorCartesian, ElbowMotionKeepsThePose) {
  Emulator emulator(panda());
  emulator.start_motion(ControlMode::kCartesianPose);
  const rt::RobotState start = emulator.state();
  const Transform initial = pose_of(start.O_T_EE);
  double worst = 0.0;
  for (int k = 0; k <= 10000; ++k) {
    const double angle = M_PI / 10.0 * (1.0 - std::cos(M_PI / 5.0 * k * kDt));
    Command command = pose_command(initial);
    command.elbow = std::array<double, 2>{start.elbow[0] + angle, start.elbow[1]};
    command.motion_finished = k == 10000;
    emulator.step(&command);
    const rt::RobotState& s = emulator.state();
    ASSERT_NE(s.robot_mode, rt::RobotMode::kReflex) << emulator.reflex_reason();
    if (k == 10000) break;
    EXPECT_EQ(s.elbow_c, *command.elbow);
    EXPECT_EQ(s.q_d[2], (*command.elbow)[0]);
    EXPECT_EQ(s.elbow_d[1], start.elbow[1]);
    EXPECT_LT(position_distance(pose_of(s.O_T_EE_d), initial), 1e-9);
    worst = std::max(worst, position_distance(pose_of(s.O_T_EE), initial));
    if (k == 5000) {
      EXPECT_NEAR(s.q[2], start.q[2] + M_PI / 5.0, 1e-3);
    }
  }
  EXPECT_NEAR(emulator.state().q[2], start.q[2], 1e-3);
  EXPECT_LT(worst, 1e-3);
}

// Two emulators, the same commands (with a lost command): the same states, bit for bit.
TEST(EmulatorCartesian, LockstepIsBitReproducible) {
  const auto run = [](ControllerMode controller) {
    Emulator emulator(panda());
    emulator.start_motion(ControlMode::kCartesianPose, controller);
    const Transform initial = pose_of(emulator.state().O_T_EE);
    std::vector<rt::RobotState> states;
    for (int k = 0; k < 2000; ++k) {
      Transform pose = initial;
      pose.translation.y() += 0.05 * (1.0 - std::cos(M_PI * k * kDt));
      const Command command = pose_command(pose);
      emulator.step(k == 700 ? nullptr : &command);
      states.push_back(emulator.state());
    }
    return states;
  };
  for (ControllerMode controller : {ControllerMode::kJointImpedance, ControllerMode::kCartesianImpedance}) {
    const std::vector<rt::RobotState> a = run(controller), b = run(controller);
    for (std::size_t k = 0; k < a.size(); ++k) {
      ASSERT_EQ(std::memcmp(a[k].q.data(), b[k].q.data(), sizeof(a[k].q)), 0) << k;
      ASSERT_EQ(std::memcmp(a[k].tau_J.data(), b[k].tau_J.data(), sizeof(a[k].tau_J)), 0) << k;
      ASSERT_EQ(std::memcmp(a[k].O_T_EE_c.data(), b[k].O_T_EE_c.data(), sizeof(a[k].O_T_EE_c)), 0) << k;
    }
    EXPECT_EQ(a.back().robot_mode, rt::RobotMode::kMove);
  }
}

// Hooke's law: a force on the EE held by the Cartesian impedance displaces it by F / k along each
// K axis (here K = EE, anisotropic stiffness). In equilibrium J^T (F_ext + K e) + N tau_null = 0
// splits into range(J^T) and null(J), so K e = -F_ext: the null-space joint impedance does not
// stiffen the task.
TEST(EmulatorCartesian, CartesianImpedanceObeysHookesLaw) {
  rt::EmulatorSettings settings = panda();
  settings.collision.upper_force_nominal.setConstant(1e3);
  settings.collision.upper_force_acceleration.setConstant(1e3);
  settings.collision.upper_torque_nominal.setConstant(1e3);
  settings.collision.upper_torque_acceleration.setConstant(1e3);
  const Vector3 force(4.0, -3.0, 5.0);   // base frame [N]
  rt::ExternalWrench push;
  push.link = 7;
  push.point = (settings.plant.link7_T_flange * settings.plant.F_T_EE).translation;   // at the EE origin
  push.force = force;
  push.start = 0.2;
  push.end = 10.0;
  push.ramp = 0.2;
  settings.external_wrenches = {push};
  Emulator emulator(settings);
  const Vector6 stiffness = (Vector6() << 1000, 1500, 2000, 100, 100, 100).finished();
  emulator.set_cartesian_impedance(stiffness);
  emulator.start_motion(ControlMode::kCartesianPose, ControllerMode::kCartesianImpedance);
  const Transform initial = pose_of(emulator.state().O_T_EE_d);
  const Command hold = pose_command(initial);
  for (int k = 0; k < 3000; ++k) {
    emulator.step(&hold);
    ASSERT_EQ(emulator.state().robot_mode, rt::RobotMode::kMove) << emulator.reflex_reason();
  }
  const rt::RobotState& s = emulator.state();
  const Transform now = pose_of(s.O_T_EE);
  const Vector3 displacement_K = now.rotation.transpose() * (now.translation - initial.translation);
  const Vector3 expected_K = (now.rotation.transpose() * force).cwiseQuotient(stiffness.head<3>());
  std::printf("Hooke: displacement in K %.4f %.4f %.4f mm, F/k %.4f %.4f %.4f mm\n", displacement_K.x() * 1e3,
              displacement_K.y() * 1e3, displacement_K.z() * 1e3, expected_K.x() * 1e3, expected_K.y() * 1e3,
              expected_K.z() * 1e3);
  EXPECT_LT((displacement_K - expected_K).norm(), 0.02 * expected_K.norm());
  EXPECT_LT(Vector7(s.dq.data()).norm(), 1e-4);   // at rest: critically damped, settled
}

// Robot::control(torque_cb, motion_cb): the motion generator's setpoint is published (q_d, O_T_EE_d)
// while the user's torque drives the arm: with zero torque (gravity is the robot's) the arm stays
// where it is while the commanded pose moves 5 cm and back; a torque on joint 7 turns joint 7.
TEST(EmulatorCartesian, TorqueControlWithAMotionGenerator) {
  Emulator emulator(panda());
  emulator.start_motion(ControlMode::kCartesianPose, ControllerMode::kExternalController);
  EXPECT_EQ(emulator.controller_mode(), ControllerMode::kExternalController);
  const rt::RobotState start = emulator.state();
  const Transform initial = pose_of(start.O_T_EE);
  for (int k = 0; k < 2000; ++k) {
    Transform pose = initial;
    pose.translation.y() += 0.025 * (1.0 - std::cos(M_PI * k * kDt));
    Command command = pose_command(pose);
    command.torque[6] = k < 1000 ? 0.0 : 0.005;
    emulator.step(&command);
    const rt::RobotState& s = emulator.state();
    ASSERT_EQ(s.robot_mode, rt::RobotMode::kMove) << emulator.reflex_reason();
    EXPECT_LT(position_distance(pose_of(s.O_T_EE_d), pose), 1e-9);
    EXPECT_EQ(s.tau_J_d[6], command.torque[6]);
    if (k == 999) {
      EXPECT_LT((Vector7(s.q.data()) - Vector7(start.q.data())).cwiseAbs().maxCoeff(), 1e-9);
    }
    if (k == 1000) {
      EXPECT_NEAR(s.O_T_EE_d[13], initial.translation.y() + 0.05, 1e-9);
    }
  }
  EXPECT_GT(emulator.state().dq[6], 0.1);
}

// ---------------------------------------------------------------------------------------------
// Errors: each one tripped by a purpose-built command, and nothing else

// Runs `command_at(k)` from the start until the motion ends; returns the errors that ended it.
rt::ErrorSet run_until_reflex(Emulator& emulator, ControlMode mode, const std::function<Command(int)>& command_at,
                            int max_cycles = 3000, ControllerMode controller = ControllerMode::kJointImpedance) {
  emulator.start_motion(mode, controller);
  for (int k = 0; k < max_cycles && emulator.in_motion(); ++k) {
    const Command command = command_at(k);
    emulator.step(&command);
  }
  EXPECT_EQ(emulator.state().robot_mode, rt::RobotMode::kReflex) << "no reflex";
  return rt::ErrorSet(emulator.state().last_motion_errors);
}

// A translational velocity command with jerk-limited start: jerk j until acceleration a, then
// constant acceleration (along base y).
Command ramp(int k, double jerk, double acceleration_cap, int axis = 1) {
  const double t = (k + 1) * kDt, t_ramp = acceleration_cap / jerk;
  const double v = t < t_ramp ? 0.5 * jerk * t * t : 0.5 * jerk * t_ramp * t_ramp + acceleration_cap * (t - t_ramp);
  Vector6 twist = Vector6::Zero();
  twist[axis] = v;
  return twist_command(twist);
}

// Cartesian limits scaled down for the rate tests so that the joints stay far inside theirs.
rt::EmulatorSettings slow_cartesian_limits() {
  rt::EmulatorSettings s = panda();
  s.plant.cartesian_limits.translation = {0.05, 0.5, 50.0};
  s.plant.cartesian_limits.rotation = {0.1, 1.0, 100.0};
  s.plant.cartesian_limits.elbow = {0.1, 1.0, 100.0};
  return s;
}

TEST(EmulatorCartesianErrors, VelocityAccelerationAndJerkPerAxis) {
  struct Case {
    int axis;              // 1: translation y, 4: rotation y, -1: elbow
    double jerk, cap;      // the ramp
    Error error;
  };
  // Translation limits (0.05, 0.5, 50), rotation and elbow (0.1, 1, 100):
  const Case cases[] = {
      {1, 40.0, 0.4, Error::cartesian_motion_generator_velocity_limits_violation},
      {1, 40.0, 1e9, Error::cartesian_motion_generator_velocity_discontinuity},
      {1, 60.0, 1e9, Error::cartesian_motion_generator_acceleration_discontinuity},
      {4, 80.0, 0.8, Error::cartesian_motion_generator_velocity_limits_violation},
      {4, 80.0, 1e9, Error::cartesian_motion_generator_velocity_discontinuity},
      {4, 120.0, 1e9, Error::cartesian_motion_generator_acceleration_discontinuity},
      {-1, 80.0, 0.8, Error::cartesian_motion_generator_velocity_limits_violation},
      {-1, 80.0, 1e9, Error::cartesian_motion_generator_velocity_discontinuity},
      {-1, 120.0, 1e9, Error::cartesian_motion_generator_acceleration_discontinuity},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(rt::error_name(c.error)) + " axis " + std::to_string(c.axis));
    Emulator emulator(slow_cartesian_limits());
    const double q3 = emulator.state().q[2], sign = emulator.state().elbow[1];
    double elbow = q3;
    const rt::ErrorSet errors = run_until_reflex(emulator, ControlMode::kCartesianVelocity, [&](int k) {
      if (c.axis >= 0) return ramp(k, c.jerk, c.cap, c.axis);
      Command command;   // the elbow's position integrates the same ramp's velocity, from the start
      if (k > 0) elbow += ramp(k - 1, c.jerk, c.cap, 0).O_dP_EE_c[0] * kDt;
      command.elbow = std::array<double, 2>{elbow, sign};
      return command;
    });
    expect_only(errors, c.error);
  }
}

TEST(EmulatorCartesianErrors, StartPoseAndFrame) {
  {
    Emulator emulator(panda());
    Transform away = pose_of(emulator.state().O_T_EE_c);
    away.translation.x() += 0.01;   // 1 cm: more than one cycle at 1.7 m/s
    const rt::ErrorSet e = run_until_reflex(emulator, ControlMode::kCartesianPose, [&](int) { return pose_command(away); });
    expect_only(e, Error::cartesian_position_motion_generator_start_pose_invalid);
  }
  {
    Emulator emulator(panda());
    const Transform initial = pose_of(emulator.state().O_T_EE_c);
    const rt::ErrorSet e = run_until_reflex(emulator, ControlMode::kCartesianPose, [&](int k) {
      Command command = pose_command(initial);
      if (k == 5) command.O_T_EE_c[0] *= 1.001;   // not a rotation
      return command;
    });
    expect_only(e, Error::cartesian_position_motion_generator_invalid_frame);
    EXPECT_NE(emulator.reflex_reason().find("unit rows and columns"), std::string::npos) << emulator.reflex_reason();
  }
}

TEST(EmulatorCartesianErrors, Elbow) {
  const auto elbow_command = [](const Transform& pose, double q3, double sign) {
    Command command = pose_command(pose);
    command.elbow = std::array<double, 2>{q3, sign};
    return command;
  };
  {   // the first elbow 0.01 rad from joint 3: more than one cycle at 2.175 rad/s
    Emulator emulator(panda());
    const Transform pose = pose_of(emulator.state().O_T_EE_c);
    const double q3 = emulator.state().q[2], sign = emulator.state().elbow[1];
    expect_only(run_until_reflex(emulator, ControlMode::kCartesianPose, [&](int) { return elbow_command(pose, q3 + 0.01, sign); }),
                Error::cartesian_motion_generator_start_elbow_invalid);
  }
  {   // the first elbow with the other sign
    Emulator emulator(panda());
    const Transform pose = pose_of(emulator.state().O_T_EE_c);
    const double q3 = emulator.state().q[2], sign = emulator.state().elbow[1];
    expect_only(run_until_reflex(emulator, ControlMode::kCartesianPose, [&](int) { return elbow_command(pose, q3, -sign); }),
                Error::start_elbow_sign_inconsistent);
  }
  {   // the sign flips during the motion
    Emulator emulator(panda());
    const Transform pose = pose_of(emulator.state().O_T_EE_c);
    const double q3 = emulator.state().q[2], sign = emulator.state().elbow[1];
    expect_only(run_until_reflex(emulator, ControlMode::kCartesianPose,
                                 [&](int k) { return elbow_command(pose, q3, k < 10 ? sign : -sign); }),
                Error::cartesian_motion_generator_elbow_sign_inconsistent);
  }
  {   // the elbow driven past joint 3's upper limit (2 urad away) at 9 rad/s^2, before the arm moves
    Vector7 q = kStart;
    const double q3_max = panda().plant.joint_limits.q_max[2];
    q[2] = q3_max - 2e-6;
    Emulator emulator(panda(q));
    const Transform pose = pose_of(emulator.state().O_T_EE_c);
    const double sign = emulator.state().elbow[1];
    const rt::ErrorSet e = run_until_reflex(emulator, ControlMode::kCartesianPose, [&](int k) {
      const double t = k * kDt;
      return elbow_command(pose, q[2] + 0.5 * 9.0 * t * t, sign);
    });
    expect_only(e, Error::cartesian_motion_generator_elbow_limit_violation);
  }
}

// The joint-space consequences: a Cartesian motion inside the Cartesian limits whose joint
// trajectory leaves the joints' (scaled down where needed, or a joint started near its limit).
TEST(EmulatorCartesianErrors, JointSpaceConsequences) {
  {   // joint 7 just below its upper limit, the EE turned about its own z axis (joint 7's) from rest
    Vector7 q = kStart;
    q[6] = panda().plant.joint_limits.q_max[6] - 2e-4;
    Emulator emulator(panda(q));
    const Vector3 z = pose_of(emulator.state().O_T_EE_c).rotation.col(2);
    expect_only(run_until_reflex(emulator, ControlMode::kCartesianVelocity,
                                 [&](int k) { return twist_command(linear_angular(Vector3::Zero(), 0.1 * (k + 1) * kDt * z)); }),
                Error::cartesian_motion_generator_joint_position_limits_violation);
  }
  struct Case {
    double dq_max, ddq_max, dddq_max;   // joint 1's limits for this case (the others' as the Panda's)
    double jerk, cap;                   // the Cartesian ramp (within 1.7 m/s, 13 m/s^2, 6500 m/s^3)
    Error error;
  };
  const Case cases[] = {
      {0.05, 15.0, 7500.0, 5.0, 0.5, Error::cartesian_motion_generator_joint_velocity_limits_violation},
      {2.0, 0.5, 7500.0, 50.0, 1e9, Error::cartesian_motion_generator_joint_velocity_discontinuity},
      {2.0, 15.0, 20.0, 100.0, 1e9, Error::cartesian_motion_generator_joint_acceleration_discontinuity},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(rt::error_name(c.error));
    rt::EmulatorSettings settings = panda();
    JointLimits& limits = settings.plant.joint_limits;
    // Joint 1 only: it carries the EE's y motion from kStart, and a light joint such as 7 leads its
    // command in the first milliseconds (dynamic coupling), which would trip the measured check first.
    limits.dq_max[0] = c.dq_max;
    limits.ddq_max[0] = c.ddq_max;
    limits.dddq_max[0] = c.dddq_max;
    Emulator emulator(settings);
    expect_only(run_until_reflex(emulator, ControlMode::kCartesianVelocity, [&](int k) { return ramp(k, c.jerk, c.cap); }),
                c.error);
  }
}

// With torque control next to the motion generator, the generator's checks still apply, and
// the torque's rate check too.
TEST(EmulatorCartesianErrors, TorqueWithMotionGeneratorChecksBoth) {
  {
    Emulator emulator(panda());
    expect_only(run_until_reflex(
                    emulator, ControlMode::kCartesianVelocity,
                    // 8 mm/s in one cycle: 8 m/s^2 (under 13) but 8000 m/s^3 (over 6500)
                    [](int k) { return twist_command((Vector6() << 0, k < 10 ? 0.0 : 0.008, 0, 0, 0, 0).finished()); },
                    100, ControllerMode::kExternalController),
                Error::cartesian_motion_generator_acceleration_discontinuity);
  }
  {
    Emulator emulator(panda());
    expect_only(run_until_reflex(
                    emulator, ControlMode::kCartesianVelocity,
                    [](int k) {
                      Command command = twist_command(Vector6::Zero());
                      command.torque[0] = k < 10 ? 0.0 : 5.0;   // 5000 N m/s > 1000
                      return command;
                    },
                    100, ControllerMode::kExternalController),
                Error::controller_torque_discontinuity);
  }
}

TEST(EmulatorCartesianErrors, RefusedConfiguration) {
  Emulator emulator(panda());
  EXPECT_EQ(emulator.settings().cartesian_stiffness, rt::default_cartesian_stiffness());
  EXPECT_THROW(emulator.set_cartesian_impedance((Vector6() << 5, 3000, 3000, 300, 300, 300).finished()), std::invalid_argument);
  EXPECT_THROW(emulator.set_cartesian_impedance((Vector6() << 3000, 3000, 3000, 300, 301, 300).finished()), std::invalid_argument);
  EXPECT_THROW(emulator.set_cartesian_impedance((Vector6() << NAN, 3000, 3000, 300, 300, 300).finished()), std::invalid_argument);
  EXPECT_THROW(emulator.start_motion(ControlMode::kTorque, ControllerMode::kCartesianImpedance), std::invalid_argument);
  emulator.start_motion(ControlMode::kCartesianPose, ControllerMode::kCartesianImpedance);
  EXPECT_THROW(emulator.set_cartesian_impedance(rt::default_cartesian_stiffness()), rt::InvalidOperation);
  Command command = pose_command(pose_of(emulator.state().O_T_EE_c));
  command.elbow = std::array<double, 2>{NAN, 1.0};
  emulator.step(&command);
  EXPECT_EQ(emulator.state().robot_mode, rt::RobotMode::kReflex);
  EXPECT_NE(emulator.reflex_reason().find("cartesian_pose command is not finite (elbow"), std::string::npos)
      << emulator.reflex_reason();
}

}  // namespace
}  // namespace csp::test
