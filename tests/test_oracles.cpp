// Oracle tests: every reference value in ../shared/data/franka_models.json that our model can
// reproduce, read from the file at run time (never copied from our own output).
//
// Tolerances follow the precision of each oracle, not of our code:
//  - values stored as full doubles (libfranka model dump, FK oracles): 1e-9;
//  - values printed with a fixed number of significant digits: about half a unit of the last
//    printed digit, plus the effect of the printed (rounded) joint angles where q is printed too;
//  - values from a different model (the Gaz et al. base-parameter code): the documented agreement.
// Each test says which case applies.
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support.hpp"

namespace csp::test {
namespace {

using nlohmann::json;

const json& oracles() { return franka_models().at("oracles"); }


Matrix7 matrix7(const json& values, bool column_major) {
  const Eigen::Matrix<double, 49, 1> flat = vector_from<49>(values);
  Matrix7 m;
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 7; ++c) m(r, c) = column_major ? flat[c * 7 + r] : flat[r * 7 + c];
  return m;
}

// A 4x4 homogeneous transform stored column-major (libfranka).
Transform transform_colmajor(const json& values) {
  const Eigen::Matrix<double, 16, 1> flat = vector_from<16>(values);
  Transform t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.rotation(r, c) = flat[c * 4 + r];
    t.translation[r] = flat[12 + r];
  }
  return t;
}

// libfranka's lumped load description: m_total, F_x_Ctotal, diagonal I_total.
RigidBodyInertia load_from(const json& m_total, const json& com, const json& inertia_diag) {
  RigidBodyInertia load;
  load.mass = m_total.get<double>();
  load.com = v3(com);
  load.inertia = v3(inertia_diag).asDiagonal();
  return load;
}

ModelOptions options(const std::string& inertia, const std::string& end_effector = "none") {
  ModelOptions o;
  o.inertia = inertia;
  o.end_effector = end_effector;
  return o;
}

Vector7 coriolis_of(const Model& model, const Vector7& q, const Vector7& dq) {
  Data data;
  Vector7 c;
  coriolis_torque(model, data, q, dq, c);
  return c;
}

Data kinematics_of(const Model& model, const Vector7& q) {
  Data data;
  forward_kinematics(model, data, q);
  return data;
}

// ---------------------------------------------------------------------------------------------
// Forward kinematics: kinematics.fk_oracles_computed (modified DH + hand TCP).
// Positions are stored with 12 significant digits (joint origins with 10 decimals) and rotations
// with 10 decimals, so 1e-9 is the tightest tolerance the data supports. The q of the 'ready'
// pose is itself printed with 12 digits and is used as printed. Panda and FR3 share the chain,
// so both robot files must reproduce every pose.
TEST(OracleKinematics, PosesOfFlangeHandTcpAndJointFrames) {
  constexpr double kTolerance = 1e-9;
  const json& poses = franka_models().at("kinematics").at("fk_oracles_computed").at("poses");
  for (const std::string robot : {"panda", "fr3"}) {
    const Model arm = make_model(robot, options("", "none"));
    const Model with_hand = make_model(robot, options("", "hand"));
    for (const auto& [name, pose] : poses.items()) {
      SCOPED_TRACE(robot + " pose " + name);
      const Vector7 q = v7(pose.at("q"));
      const Data data = kinematics_of(arm, q);
      EXPECT_TRUE(near(data.O_T_F.translation, v3(pose.at("flange_O_T_F").at("p")), kTolerance));
      EXPECT_TRUE(near(data.O_T_F.rotation, matrix3_rowmajor(pose.at("flange_O_T_F").at("R_rowmajor")), kTolerance));
      // Without an end effector, EE = flange.
      EXPECT_TRUE(near(data.O_T_EE.translation, data.O_T_F.translation, 0.0));

      const Data hand = kinematics_of(with_hand, q);
      EXPECT_TRUE(near(hand.O_T_EE.translation, v3(pose.at("hand_tcp_O_T_EE").at("p")), kTolerance));
      EXPECT_TRUE(near(hand.O_T_EE.rotation, matrix3_rowmajor(pose.at("hand_tcp_O_T_EE").at("R_rowmajor")), kTolerance));

      const json& origins = pose.at("joint_frame_origins_1to7");
      for (int i = 0; i < kNumJoints; ++i) {
        SCOPED_TRACE("joint frame " + std::to_string(i + 1));
        EXPECT_TRUE(near(data.O_T_joint[i].translation, v3(origins.at(i)), kTolerance));
        EXPECT_TRUE(near(frame_pose(data, static_cast<Frame>(i)).translation, v3(origins.at(i)), kTolerance));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// libfranka's Panda model library (libfcimodels) dumped at full double precision, reproduced by
// the base-parameter-equivalent fit 'libfranka_fit' (the JSON states < 1e-9 for gravity, mass and
// Coriolis without load). 1e-9 absolute is therefore a fair bound for the no-load cases.
class OracleLibfrankaDump : public ::testing::Test {
 protected:
  const json& dump = oracles().at("panda_libfranka_model_dump");
  const Model model = make_model("panda", options("libfranka_fit"));
  static constexpr double kNoLoadTolerance = 1e-9;
};

TEST_F(OracleLibfrankaDump, ZeroPoseNoLoad) {
  const json& c = dump.at("zero_no_load");
  const Vector7 q = v7(c.at("q"));
  EXPECT_TRUE(near(gravity_of(model, q), v7(c.at("gravity")), kNoLoadTolerance));
  EXPECT_TRUE(near(mass_of(model, q), matrix7(c.at("mass_colmajor"), true), kNoLoadTolerance));
}

TEST_F(OracleLibfrankaDump, ReadyPoseNoLoad) {
  const json& c = dump.at("ready_no_load");
  const Vector7 q = v7(c.at("q"));
  EXPECT_TRUE(near(gravity_of(model, q), v7(c.at("gravity")), kNoLoadTolerance));
  EXPECT_TRUE(near(mass_of(model, q), matrix7(c.at("mass_colmajor"), true), kNoLoadTolerance));
  EXPECT_TRUE(near(coriolis_of(model, q, Vector7::Ones()), v7(c.at("coriolis_at_dq_all_ones")), kNoLoadTolerance));
  EXPECT_TRUE(near(kinematics_of(model, q).O_T_F.translation, v3(c.at("pose_flange_p")), kNoLoadTolerance));
}

// Hand + 0.5 kg load given to libfranka as one lumped body (m_total, F_x_Ctotal, I_total) with
// F_T_EE of the hand. We build it the same way: no end effector in the config, F_T_EE taken from
// the dump, the lumped body as the load.
TEST_F(OracleLibfrankaDump, ReadyPoseHandAndLoad) {
  const json& c = dump.at("ready_hand_and_load");
  const Vector7 q = v7(c.at("q"));
  ModelParameters p = model.parameters();
  p.F_T_EE = transform_colmajor(c.at("F_T_EE_column_major"));
  p.load = load_from(c.at("m_total"), c.at("F_x_Ctotal"), c.at("I_total_diag"));
  const Model loaded(p);

  // Gravity depends only on the load's mass and CoM (affine in them) and the EE position only on
  // kinematics: both reproducible to 1e-6 as asked (observed ~1e-14).
  EXPECT_TRUE(near(gravity_of(loaded, q), v7(c.at("gravity")), 1e-6));
  EXPECT_TRUE(near(kinematics_of(loaded, q).O_T_EE.translation, v3(c.at("pose_EE_p")), 1e-6));

  // Coriolis also depends on the load's rotational inertia, and libfcimodels does not treat
  // I_total as an ordinary rigid body lumped on link 7: no rigid-body interpretation of
  // I_total_diag (CoM axes, EE axes, zero) reproduces this vector, and the same library's
  // loaded mass matrix differs from rigid lumping by up to 2e-3 kg m^2 (see
  // panda_real_robot_panda_model_tests 'check'; franka-rs reports a non-affine payload effect).
  // An independent Python RNEA with the same lumping gives the same ~1.4e-2 N m difference, so
  // this is not a CSP bug. We therefore only assert what the data supports: agreement within the
  // size of the load-inertia contribution itself (2e-2 N m, vs. entries of up to 3 N m), which
  // still checks the arm and the load's mass/CoM terms of the Coriolis vector.
  EXPECT_TRUE(near(coriolis_of(loaded, q, Vector7::Ones()), v7(c.at("coriolis_at_dq_all_ones")), 2e-2));
}

// ---------------------------------------------------------------------------------------------
// franka_ros gravity tests: libfranka Panda model output printed with 6 significant digits, for
// two gravity directions. 1e-4 covers half a unit of the 6th digit of the largest entry (18.17)
// with margin.
TEST(OracleFrankaRosGravity, LibfrankaFitReproducesAllCases) {
  const json& tests = oracles().at("panda_libfranka_model_franka_ros_gravity_tests");
  ASSERT_EQ(tests.at("m_total").get<double>(), 0.0);
  const Model model = make_model("panda", options("libfranka_fit"));
  int index = 0;
  for (const json& c : tests.at("cases")) {
    SCOPED_TRACE("case " + std::to_string(index++));
    const Model tilted = with_gravity(model, v3(c.at("gravity_earth")));
    EXPECT_TRUE(near(gravity_of(tilted, v7(c.at("q"))), v7(c.at("g")), 1e-4));
  }
}

// ---------------------------------------------------------------------------------------------
// franka::Model on a real Panda with the default hand load (JeanElsner/panda_model test data).
// Everything, q included, is printed with 6 significant digits.
TEST(OracleRealPandaModel, GravityPoseAndMassWithHand) {
  const json& c = oracles().at("panda_real_robot_panda_model_tests");
  const Model model = make_model("panda", options("libfranka_fit", "hand"));
  const Vector7 q = v7(c.at("q"));

  // Gravity: the 'check' claims 1e-6, which holds relative to the printed digits; in absolute
  // terms 21.8563 carries +-5e-5 of print rounding and the rounded q (up to 5e-6 rad on joints 4
  // and 6) moves g by up to ~1e-4. 1e-4 is also the source's own test tolerance.
  EXPECT_TRUE(near(gravity_of(model, q), v7(c.at("gravity")), 1e-4));

  Eigen::Matrix4d expected_pose;
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) expected_pose(r, k) = c.at("O_T_EE_rowmajor").at(r).at(k).get<double>();
  const Transform O_T_EE = kinematics_of(model, q).O_T_EE;
  // Position to 1e-6 m as the 'check' says (printed to 1e-6 m / 6 digits).
  EXPECT_TRUE(near(O_T_EE.translation, Vector3(expected_pose.topRightCorner<3, 1>()), 1e-6));
  // Rotation entries: printed to 5-6 digits (0.99999 is 0.9999902 rounded), and the rounded q
  // tilts the frame by up to ~1e-5 rad, so 2e-5.
  EXPECT_TRUE(near(O_T_EE.rotation, Matrix3(expected_pose.topLeftCorner<3, 3>()), 2e-5));

  // Mass diagonal: NOT expected to match tightly ('check': libfcimodels' payload handling differs
  // from rigid lumping by up to 2e-3 kg m^2). Guard that it stays within that documented gap.
  EXPECT_TRUE(near(Vector7(mass_of(model, q).diagonal()), v7(c.at("mass_diag")), 2.5e-3));
}

// ---------------------------------------------------------------------------------------------
// echo_robot_state output of a real, idle Panda with the Franka Hand (docs example).
TEST(OracleRealPandaStateExample, EndEffectorPoseAndMeasuredTorques) {
  const json& c = oracles().at("panda_real_robot_state_docs_example");
  const std::string check = c.at("check").get<std::string>();
  ModelOptions o = options("libfranka_fit", "hand");
  const Model model = make_model("panda", o);
  // The configured hand is the one the robot reported.
  EXPECT_DOUBLE_EQ(model.parameters().end_effector.mass, c.at("m_ee").get<double>());
  EXPECT_TRUE(near(model.parameters().end_effector.com, v3(c.at("F_x_Cee")), 0.0));
  EXPECT_TRUE(near(Vector3(model.parameters().end_effector.inertia.diagonal()), v3(c.at("I_ee_diag")), 0.0));

  const Vector7 q = v7(c.at("q"));
  const Transform measured = transform_colmajor(c.at("O_T_EE_column_major"));
  const Transform O_T_EE = kinematics_of(model, q).O_T_EE;
  // 'check': nominal DH + hand TCP reproduce the position to 2e-6 m.
  EXPECT_TRUE(near(O_T_EE.translation, measured.translation, 2e-6));
  // Orientation: 6 printed digits of q and of R; ~1e-5 as above.
  EXPECT_TRUE(near(O_T_EE.rotation, measured.rotation, 2e-5));

  // 'check' lists the libfranka-model gravity at this q with 4 decimals: our libfranka_fit + hand
  // must round to it, i.e. differ by at most half a unit of the 4th decimal.
  const std::regex list(R"(at this q = \[([^\]]*)\])");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(check, match, list)) << check;
  const json printed_g = json::parse("[" + match[1].str() + "]");
  const Vector7 g = gravity_of(model, q);
  EXPECT_TRUE(near(g, v7(printed_g), 5e-5 + 1e-12));

  // Physics: tau_J (link-side torque sensors) minus the gravity model is what libfranka reports
  // as the external torque, up to sensor offsets and the low-pass filter of
  // tau_ext_hat_filtered. The 'check' says 'within ~0.14 N m' (observed 0.140 on joint 2), so we
  // allow 0.15 N m; this is a real measurement, the model cannot do better.
  const Vector7 tau_ext = v7(c.at("tau_J")) - g;
  EXPECT_TRUE(near(tau_ext, v7(c.at("tau_ext_hat_filtered")), 0.15));
}

// ---------------------------------------------------------------------------------------------
// libfranka 0.21.2's FR3 unit tests (Pinocchio + fr3.urdf), values printed with 6 significant
// digits (e.g. 2.73892: half a unit is 5e-6). libfranka's own test tolerance, 1e-5, is about two
// half-units for the entries of order 1 and one for the largest (|v| < 10): the tightest honest
// bound for these printed numbers.
class OracleFr3Libfranka : public ::testing::Test {
 protected:
  const json& tests = oracles().at("fr3_libfranka_model_tests");
  const Model model = with_gravity(make_model("fr3"), v3(tests.at("gravity_earth")));
  static constexpr double kTolerance = 1e-5;
};

TEST_F(OracleFr3Libfranka, ZeroPoseNoLoad) {
  const json& c = tests.at("q_zero_no_load");
  EXPECT_TRUE(near(gravity_of(model, Vector7::Zero()), v7(c.at("gravity")), kTolerance));
  EXPECT_TRUE(near(mass_of(model, Vector7::Zero()), matrix7(c.at("mass_rowmajor"), false), kTolerance));
}

TEST_F(OracleFr3Libfranka, ZeroPoseHandLikeLoad) {
  const json& c = tests.at("q_zero_hand_like_load");
  const Model loaded = with_load(model, load_from(c.at("m_total"), c.at("F_x_Ctotal"), c.at("I_total_diag")));
  EXPECT_TRUE(near(gravity_of(loaded, Vector7::Zero()), v7(c.at("gravity")), kTolerance));
  EXPECT_TRUE(near(coriolis_of(loaded, Vector7::Zero(), Vector7::Ones()), v7(c.at("coriolis_at_dq_all_ones")), kTolerance));
  EXPECT_TRUE(near(mass_of(loaded, Vector7::Zero()), matrix7(c.at("mass_rowmajor"), false), kTolerance));
}

// ---------------------------------------------------------------------------------------------
// Values the data helper computed with its own RNEA (printed with 8 significant digits; half a
// unit of the 8th digit is <= 5e-7 for |v| < 100 and <= 5e-8 for |v| < 10).
class OracleHelperComputed : public ::testing::Test {
 protected:
  const json& helper = oracles().at("computed_by_helper");
  const json& poses = franka_models().at("kinematics").at("fk_oracles_computed").at("poses");
  const Vector7 q_zero = v7(poses.at("zero").at("q"));
  const Vector7 q_ready = v7(poses.at("ready").at("q"));
};

TEST_F(OracleHelperComputed, PandaGaz2019Gravity) {
  const Model model = make_model("panda", options("gaz2019"));
  EXPECT_TRUE(near(gravity_of(model, q_zero), v7(helper.at("panda_gaz_phat_gravity").at("zero")), 1e-6));
  EXPECT_TRUE(near(gravity_of(model, q_ready), v7(helper.at("panda_gaz_phat_gravity").at("ready")), 1e-6));
}

TEST_F(OracleHelperComputed, Fr3GravityAndMassDiagonal) {
  const Model model = make_model("fr3");
  EXPECT_TRUE(near(gravity_of(model, q_zero), v7(helper.at("fr3_franka_description_gravity").at("zero")), 1e-6));
  EXPECT_TRUE(near(gravity_of(model, q_ready), v7(helper.at("fr3_franka_description_gravity").at("ready")), 1e-6));
  EXPECT_TRUE(near(Vector7(mass_of(model, q_ready).diagonal()), v7(helper.at("fr3_franka_description_mass_diag_ready")),
                   1e-7));
}

// The Gaz et al. symbolic code model (g0 = 9.80665) is built from the identified base parameters
// pi_hat_R-E, not from any of our link-parameter sets, so no set reproduces it to its 6 printed
// digits. The JSON (dynamics.panda_gaz2019_code_model) says what it is comparable with: it
// reproduces libfranka's own Panda model to ~1e-2 N m / ~1e-4 kg m^2. So we compare our
// libfranka-equivalent set, under the same g0, at those documented levels (observed: 1.1e-2 N m
// on joint 2 at q = 0, 8e-5 kg m^2), and our physical Gaz p-hat set, which the paper's notes
// call 'slightly different', at 0.1 N m (observed 8e-2 N m; < 0.5 % of the 18.5 N m joint 4 load).
TEST_F(OracleHelperComputed, GazCodeModelAgainstLibfrankaEquivalentModel) {
  const json& code = helper.at("panda_gaz_code_model_gravity_g0_9_80665");
  const double g0 = franka_models().at("dynamics").at("panda_gaz2019_code_model").at("g0").get<double>();
  const Vector3 gravity(0.0, 0.0, -g0);

  const Model libfranka = with_gravity(make_model("panda", options("libfranka_fit")), gravity);
  EXPECT_TRUE(near(gravity_of(libfranka, q_zero), v7(code.at("zero")), 1.5e-2));
  EXPECT_TRUE(near(gravity_of(libfranka, q_ready), v7(code.at("ready")), 1.5e-2));
  EXPECT_TRUE(near(Vector7(mass_of(libfranka, q_ready).diagonal()), v7(code.at("mass_diag_ready")), 1e-4));

  const Model gaz = with_gravity(make_model("panda", options("gaz2019")), gravity);
  EXPECT_TRUE(near(gravity_of(gaz, q_zero), v7(code.at("zero")), 0.1));
  EXPECT_TRUE(near(gravity_of(gaz, q_ready), v7(code.at("ready")), 0.1));
}

// ---------------------------------------------------------------------------------------------
// Gaz et al. 2019 friction (dynamics.panda_gaz2019_friction): values printed with 9-10
// significant digits (all |v| < 1), so 1e-9.
class OracleGazFriction : public ::testing::Test {
 protected:
  const json& friction = franka_models().at("dynamics").at("panda_gaz2019_friction");
  const FrictionModel model = [] {
    ModelOptions o;
    o.friction = "gaz2019";
    return make_model("panda", o).parameters().friction;
  }();
};

TEST_F(OracleGazFriction, LoadedParametersAreTheCorrectedOnes) {
  ASSERT_EQ(model.type, FrictionModel::Type::kGazSigmoid);
  EXPECT_TRUE(near(model.phi1, v7(friction.at("FI_1_Nm")), 0.0));
  EXPECT_TRUE(near(model.phi2, v7(friction.at("FI_2_s_per_rad")), 0.0));
  EXPECT_TRUE(near(model.phi3, v7(friction.at("FI_3_rad_per_s")), 0.0));
  // Seed paper errata (data README): phi1 of joint 2 misprinted 8.7224e+03, phi3 of joint 1
  // misprinted 1.0336e+01. The config must hold the corrected values.
  EXPECT_EQ(model.phi1[1], 0.87224);
  EXPECT_EQ(model.phi3[0], 0.039533);
}

TEST_F(OracleGazFriction, DerivedValuesAtUnitSpeedAndAsymptotes) {
  const json& derived = friction.at("derived_computed");
  EXPECT_TRUE(near(friction_torque(model, Vector7::Constant(1.0)), v7(derived.at("tau_f_at_dq_plus_1")), 1e-9));
  EXPECT_TRUE(near(friction_torque(model, Vector7::Constant(-1.0)), v7(derived.at("tau_f_at_dq_minus_1")), 1e-9));
  // At |dq| = 100 rad/s, exp(-phi2 |dq|) < 1e-200 for every joint: the sigmoid has saturated.
  EXPECT_TRUE(near(friction_torque(model, Vector7::Constant(100.0)), v7(derived.at("asymptote_dq_to_plus_inf")), 1e-9));
  EXPECT_TRUE(near(friction_torque(model, Vector7::Constant(-100.0)), v7(derived.at("asymptote_dq_to_minus_inf")), 1e-9));
  // The law is zero at rest (README erratum: a function of dq with a minus sign).
  EXPECT_TRUE(near(friction_torque(model, Vector7::Zero()), Vector7::Zero(), 1e-15));
}

}  // namespace
}  // namespace csp::test
