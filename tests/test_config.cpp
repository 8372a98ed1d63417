// Robot files (configs/robots/*.yaml) and their loader (dynamics/src/robot_config.cpp):
//  - every number the loader exposes equals the number in ../shared/data/franka_models.json, exactly;
//  - FR3 position-based velocity limits follow the published formula, computed here from the JSON;
//  - every validation rule of docs/robot-config.md rejects a broken file with one message naming the
//    file, the key path and what was expected. Broken files are made at test time from the real
//    panda.yaml by small text edits, so they follow the real file as it changes.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support.hpp"

namespace csp::test {
namespace {

using nlohmann::json;


// The JSON's {xx, xy, xz, yy, yz, zz} inertia as a symmetric matrix.
Matrix3 inertia_from(const json& i) {
  Matrix3 m;
  m << i.at("xx").get<double>(), i.at("xy").get<double>(), i.at("xz").get<double>(),  //
      i.at("xy").get<double>(), i.at("yy").get<double>(), i.at("yz").get<double>(),    //
      i.at("xz").get<double>(), i.at("yz").get<double>(), i.at("zz").get<double>();
  return m;
}

// Exact equality with the worst entry in the failure message.
template <typename A, typename B>
::testing::AssertionResult same(const Eigen::MatrixBase<A>& actual, const Eigen::MatrixBase<B>& expected) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    return ::testing::AssertionFailure() << "size mismatch";
  for (Eigen::Index r = 0; r < actual.rows(); ++r)
    for (Eigen::Index c = 0; c < actual.cols(); ++c)
      if (actual(r, c) != expected(r, c))
        return ::testing::AssertionFailure() << "entry (" << r << ", " << c << "): loaded " << actual(r, c)
                                             << ", data file " << expected(r, c);
  return ::testing::AssertionSuccess();
}

template <typename Map>
std::vector<std::string> keys_of(const Map& map) {
  std::vector<std::string> out;
  for (const auto& [name, value] : map) out.push_back(name);
  return out;
}

const json& data_file() { return franka_models(); }

// ---------------------------------------------------------------------------------------------
// The robot files carry the data file's numbers, exactly.

void expect_mdh_and_flange(const RobotConfig& config) {
  const json& rows = data_file().at("kinematics").at("mdh_panda_fr3").at("rows");
  ASSERT_EQ(rows.size(), 8u);   // 7 joints + the fixed flange row
  for (int i = 0; i < kNumJoints; ++i) {
    SCOPED_TRACE("MDH row " + std::to_string(i + 1));
    const json& row = rows.at(i);
    EXPECT_EQ(config.mdh[i].a, row.at("a").get<double>());
    EXPECT_EQ(config.mdh[i].d, row.at("d").get<double>());
    EXPECT_EQ(config.mdh[i].alpha, row.at("alpha").get<double>());
    EXPECT_EQ(config.mdh[i].theta_offset, row.at("theta_offset").get<double>());
  }
  // The flange row is exposed only as the fixed transform it builds.
  const json& flange = rows.at(7);
  ASSERT_EQ(flange.at("joint").get<std::string>(), "flange");
  const Transform expected = mdh_transform(
      {flange.at("a").get<double>(), flange.at("d").get<double>(), flange.at("alpha").get<double>(),
       flange.at("theta_offset").get<double>()},
      0.0);
  EXPECT_TRUE(same(config.link7_T_flange.rotation, expected.rotation));
  EXPECT_TRUE(same(config.link7_T_flange.translation, expected.translation));
}

void expect_hand(const RobotConfig& config) {
  ASSERT_EQ(keys_of(config.end_effectors), std::vector<std::string>{"hand"});
  const EndEffectorDescription& hand = config.end_effectors.at("hand");
  const json& tcp = data_file().at("kinematics").at("franka_hand_tcp");
  EXPECT_TRUE(same(hand.F_T_EE.translation, v3(tcp.at("F_T_EE_translation"))));
  const double angle = tcp.at("F_T_EE_rotation_about_flange_z").get<double>();
  EXPECT_TRUE(same(hand.F_T_EE.rotation, Eigen::AngleAxisd(angle, Vector3::UnitZ()).toRotationMatrix()));
  EXPECT_TRUE(hand.F_T_EE.rotation.isApprox(matrix3_rowmajor(tcp.at("F_T_EE_exact_rotation_rowmajor")), 1e-15));

  const json& ee = data_file().at("dynamics").at("franka_hand").at("libfranka_default_end_effector");
  EXPECT_EQ(hand.inertia.mass, ee.at("m_ee").get<double>());
  EXPECT_TRUE(same(hand.inertia.com, v3(ee.at("F_x_Cee"))));
  EXPECT_TRUE(same(hand.inertia.inertia, matrix3_rowmajor(ee.at("I_ee_rowmajor"))));
}

void expect_joint_limits(const JointLimits& limits, const json& expected) {
  EXPECT_TRUE(same(limits.q_min, v7(expected.at("q_min"))));
  EXPECT_TRUE(same(limits.q_max, v7(expected.at("q_max"))));
  EXPECT_TRUE(same(limits.dq_max, v7(expected.at("dq_max"))));
  EXPECT_TRUE(same(limits.ddq_max, v7(expected.at("ddq_max"))));
  EXPECT_TRUE(same(limits.dddq_max, v7(expected.at("dddq_max"))));
  EXPECT_TRUE(same(limits.tau_max, v7(expected.at("tau_max"))));
  EXPECT_TRUE(same(limits.dtau_max, v7(expected.at("dtau_max"))));
}

void expect_cartesian_limits(const CartesianLimits& limits, const json& expected) {
  const auto expect_axis = [](const CartesianLimits::Axis& axis, const json& e) {
    EXPECT_EQ(axis.v_max, e.at("v_max").get<double>());
    EXPECT_EQ(axis.a_max, e.at("a_max").get<double>());
    EXPECT_EQ(axis.j_max, e.at("j_max").get<double>());
  };
  {
    SCOPED_TRACE("translation");
    expect_axis(limits.translation, expected.at("translation"));
  }
  {
    SCOPED_TRACE("rotation");
    expect_axis(limits.rotation, expected.at("rotation"));
  }
  {
    SCOPED_TRACE("elbow");
    expect_axis(limits.elbow, expected.at("elbow"));
  }
}

// `links` of a data-file set, from its first entry named `first_link` (1 or "link1"), 7 entries.
void expect_links(const InertiaSet& set, const json& links, std::size_t first) {
  ASSERT_GE(links.size(), first + kNumJoints);
  for (int i = 0; i < kNumJoints; ++i) {
    SCOPED_TRACE("link " + std::to_string(i + 1));
    const json& link = links.at(first + static_cast<std::size_t>(i));
    const json& name = link.at("link");
    EXPECT_TRUE(name == json(i + 1) || name == json("link" + std::to_string(i + 1))) << name;
    // The loader has no place for a rotated inertial frame: the data file must not have one.
    if (link.contains("com_rpy")) {
      EXPECT_TRUE(same(v3(link.at("com_rpy")), Vector3::Zero()));
    }
    EXPECT_EQ(set.links[i].mass, link.at("mass").get<double>());
    EXPECT_TRUE(same(set.links[i].com, v3(link.at("com_xyz"))));
    EXPECT_TRUE(same(set.links[i].inertia, inertia_from(link.at("inertia"))));
  }
}

void expect_sigmoid(const FrictionModel& friction, const json& expected) {
  EXPECT_EQ(friction.type, FrictionModel::Type::kGazSigmoid);
  EXPECT_TRUE(same(friction.phi1, v7(expected.at("FI_1_Nm"))));
  EXPECT_TRUE(same(friction.phi2, v7(expected.at("FI_2_s_per_rad"))));
  EXPECT_TRUE(same(friction.phi3, v7(expected.at("FI_3_rad_per_s"))));
}

void expect_linear(const FrictionModel& friction, const Vector7& viscous, const Vector7& coulomb,
                   const Vector7& offset) {
  EXPECT_EQ(friction.type, FrictionModel::Type::kLinear);
  EXPECT_TRUE(same(friction.viscous, viscous));
  EXPECT_TRUE(same(friction.coulomb, coulomb));
  EXPECT_TRUE(same(friction.offset, offset));
}

TEST(ConfigData, PandaFileCarriesTheDataFileNumbers) {
  const RobotConfig config = load_robot_config(robot_file("panda"));
  EXPECT_EQ(config.name, "panda");
  expect_mdh_and_flange(config);
  expect_hand(config);

  const json& limits = data_file().at("limits").at("panda");
  ASSERT_EQ(keys_of(config.joint_limits), std::vector<std::string>{"franka_docs"});
  EXPECT_EQ(config.default_joint_limits, "franka_docs");
  const JointLimits& joint = config.joint_limits.at("franka_docs");
  expect_joint_limits(joint, limits.at("joint"));
  EXPECT_FALSE(joint.position_based_velocity);
  expect_cartesian_limits(config.cartesian_limits, limits.at("cartesian"));

  const json& dynamics = data_file().at("dynamics");
  ASSERT_EQ(keys_of(config.inertia_sets), (std::vector<std::string>{"franka_ros_urdf", "gaz2019", "libfranka_fit"}));
  EXPECT_EQ(config.default_inertia, "gaz2019");
  {
    SCOPED_TRACE("gaz2019");
    EXPECT_TRUE(config.inertia_sets.at("gaz2019").physical);
    expect_links(config.inertia_sets.at("gaz2019"), dynamics.at("panda_gaz2019_feasible").at("links"), 0);
  }
  {
    SCOPED_TRACE("franka_ros_urdf");   // the data file lists link0 first, then link1..7, hand, fingers
    EXPECT_TRUE(config.inertia_sets.at("franka_ros_urdf").physical);
    expect_links(config.inertia_sets.at("franka_ros_urdf"), dynamics.at("panda_franka_ros_urdf").at("links"), 1);
  }
  {
    SCOPED_TRACE("libfranka_fit");
    EXPECT_FALSE(config.inertia_sets.at("libfranka_fit").physical);
    expect_links(config.inertia_sets.at("libfranka_fit"),
                 dynamics.at("panda_libfranka_model_equivalent_fit").at("links"), 0);
  }

  ASSERT_EQ(keys_of(config.friction_sets),
            (std::vector<std::string>{"gaz2019", "gaz2019_linear_cls", "gaz2019_linear_osi"}));
  EXPECT_EQ(config.default_friction, "gaz2019");
  {
    SCOPED_TRACE("gaz2019 friction");
    expect_sigmoid(config.friction_sets.at("gaz2019"), dynamics.at("panda_gaz2019_friction"));
  }
  const json& linear = dynamics.at("panda_gaz2019_linear_friction_alternatives");
  for (const auto& [set, column] : {std::pair{"gaz2019_linear_cls", "CLS"}, std::pair{"gaz2019_linear_osi", "OSI"}}) {
    SCOPED_TRACE(set);
    const json& c = linear.at(column);
    expect_linear(config.friction_sets.at(set), v7(c.at("f_v")), v7(c.at("f_c")), v7(c.at("f_o")));
  }
  // No armature: the data file's only Panda value is a simulator's class default, not identified.
  EXPECT_EQ(config.armature.values, Vector7::Zero());
  EXPECT_EQ(config.armature.source, "");
}

TEST(ConfigData, Fr3FileCarriesTheDataFileNumbers) {
  const RobotConfig config = load_robot_config(robot_file("fr3"));
  EXPECT_EQ(config.name, "fr3");
  expect_mdh_and_flange(config);
  expect_hand(config);

  const json& limits = data_file().at("limits").at("fr3");
  const json& sets = limits.at("position_based_velocity_limit").at("parameter_sets");
  ASSERT_EQ(keys_of(config.joint_limits), (std::vector<std::string>{"docs_2025_10", "libfranka_0_15"}));
  EXPECT_EQ(config.default_joint_limits, "docs_2025_10");
  const std::pair<const char*, const char*> pairs[] = {{"docs_2025_10", "docs_2025_10_current"},
                                                       {"libfranka_0_15", "libfranka_hardcoded_and_test_urdf"}};
  for (const auto& [name, data_name] : pairs) {
    SCOPED_TRACE(name);
    const JointLimits& joint = config.joint_limits.at(name);
    const json& set = sets.at(data_name);
    EXPECT_TRUE(joint.position_based_velocity);
    EXPECT_TRUE(same(joint.q_min, v7(set.at("q_min"))));
    EXPECT_TRUE(same(joint.q_max, v7(set.at("q_max"))));
    EXPECT_TRUE(same(joint.dq_max, v7(set.at("dq_max"))));
    EXPECT_TRUE(same(joint.dq_offset, v7(set.at("dq_offset"))));
    EXPECT_TRUE(same(joint.ddq_dec, v7(set.at("ddq_dec"))));
    // Acceleration, jerk, torque and torque-rate limits are those of limits.fr3.joint for both sets
    // (libfranka 0.15's rate limiter uses the same values: see limits.fr3.libfranka_rate_limiter_fr3).
    EXPECT_TRUE(same(joint.ddq_max, v7(limits.at("joint").at("ddq_max"))));
    EXPECT_TRUE(same(joint.dddq_max, v7(limits.at("joint").at("dddq_max"))));
    EXPECT_TRUE(same(joint.tau_max, v7(limits.at("joint").at("tau_max"))));
    EXPECT_TRUE(same(joint.dtau_max, v7(limits.at("joint").at("dtau_max"))));
    const json& limiter = limits.at("libfranka_rate_limiter_fr3");
    EXPECT_TRUE(same(joint.ddq_max, Vector7::Constant(limiter.at("ddq_max").get<double>())));
    EXPECT_TRUE(same(joint.dddq_max, Vector7::Constant(limiter.at("dddq_max").get<double>())));
    EXPECT_TRUE(same(joint.dtau_max, Vector7::Constant(limiter.at("dtau_max").get<double>())));
  }
  {
    // limits.fr3.joint is the current docs table: the whole block, position-based parameters included.
    SCOPED_TRACE("docs_2025_10 = limits.fr3.joint");
    const JointLimits& joint = config.joint_limits.at("docs_2025_10");
    expect_joint_limits(joint, limits.at("joint"));
    EXPECT_TRUE(same(joint.dq_offset, v7(limits.at("joint").at("dq_offset"))));
    EXPECT_TRUE(same(joint.ddq_dec, v7(limits.at("joint").at("ddq_dec"))));
  }
  expect_cartesian_limits(config.cartesian_limits, limits.at("cartesian"));

  ASSERT_EQ(keys_of(config.inertia_sets), std::vector<std::string>{"franka_description"});
  EXPECT_EQ(config.default_inertia, "franka_description");
  EXPECT_TRUE(config.inertia_sets.at("franka_description").physical);
  expect_links(config.inertia_sets.at("franka_description"),
               data_file().at("dynamics").at("fr3_franka_description").at("links"), 1);   // after link0

  ASSERT_EQ(keys_of(config.friction_sets), std::vector<std::string>{"mujoco_menagerie"});
  EXPECT_EQ(config.default_friction, "none");
  const json& joint_params = data_file().at("dynamics").at("fr3_mujoco_menagerie").at("joint_params");
  // MuJoCo damping -> viscous, frictionloss -> coulomb, no offset.
  expect_linear(config.friction_sets.at("mujoco_menagerie"), v7(joint_params.at("damping")),
                v7(joint_params.at("frictionloss")), Vector7::Zero());
  // The motors' armature, with its source.
  EXPECT_TRUE(same(config.armature.values, v7(joint_params.at("armature"))));
  EXPECT_NE(config.armature.source.find("mujoco_menagerie franka_fr3/fr3.xml"), std::string::npos) << config.armature.source;
  // A model has none unless its caller adds the robot file's (the plant's is the scenario's to take).
  EXPECT_EQ(model_parameters(config, {}).armature, Vector7::Zero());
}

// The defaults build a model with exactly these sets, and "none" is always available.
TEST(ConfigData, DefaultsAndBuiltInNamesSelectTheDocumentedSets) {
  const RobotConfig panda = load_robot_config(robot_file("panda"));
  const ModelParameters p = model_parameters(panda, {});
  EXPECT_EQ(p.links[0].mass, panda.inertia_sets.at("gaz2019").links[0].mass);
  EXPECT_TRUE(p.physically_consistent);
  EXPECT_EQ(p.friction.type, FrictionModel::Type::kGazSigmoid);
  EXPECT_EQ(p.end_effector.mass, 0.0);
  EXPECT_TRUE(same(p.F_T_EE.translation, Vector3::Zero()));
  EXPECT_TRUE(same(p.gravity, Vector3(0.0, 0.0, -9.81)));

  ModelOptions options;
  options.inertia = "libfranka_fit";
  options.friction = "none";
  options.end_effector = "hand";
  const ModelParameters q = model_parameters(panda, options);
  EXPECT_FALSE(q.physically_consistent);
  EXPECT_EQ(q.friction.type, FrictionModel::Type::kNone);
  EXPECT_EQ(q.end_effector.mass, panda.end_effectors.at("hand").inertia.mass);
  EXPECT_TRUE(same(q.F_T_EE.translation, panda.end_effectors.at("hand").F_T_EE.translation));

  const ModelParameters fr3 = model_parameters(load_robot_config(robot_file("fr3")), {});
  EXPECT_EQ(fr3.friction.type, FrictionModel::Type::kNone);   // the FR3 file's default friction is none
}

// ---------------------------------------------------------------------------------------------
// Joint velocity limits: FR3 position based, Panda constant.

const json& fr3_velocity_limit() { return data_file().at("limits").at("fr3").at("position_based_velocity_limit"); }

// The published formulas (limits.fr3.position_based_velocity_limit.formula_upper / formula_lower).
double upper_formula(double q, double q_max, double dq_max, double dq_offset, double ddq_dec) {
  return std::min(dq_max, std::max(0.0, -dq_offset + std::sqrt(std::max(0.0, 2.0 * ddq_dec * (q_max - q)))));
}
double lower_formula(double q, double q_min, double dq_max, double dq_offset, double ddq_dec) {
  return std::max(-dq_max, std::min(0.0, dq_offset - std::sqrt(std::max(0.0, 2.0 * ddq_dec * (q - q_min)))));
}

JointLimits fr3_limits(const std::string& set) {
  ModelOptions options;
  options.joint_limits = set;
  return make_model("fr3", options).parameters().joint_limits;
}

TEST(ConfigVelocityLimits, Fr3FollowsThePublishedFormulaForBothSets) {
  // The data file states the formula; the test below implements exactly that text.
  EXPECT_EQ(fr3_velocity_limit().at("formula_upper").get<std::string>(),
            "dq_max_i(q_i) = min(dq_max_i, max(0, -dq_offset_i + sqrt(max(0, 2*ddq_dec_i*(q_max_i - q_i)))))");
  EXPECT_EQ(fr3_velocity_limit().at("formula_lower").get<std::string>(),
            "dq_min_i(q_i) = max(-dq_max_i, min(0, dq_offset_i - sqrt(max(0, 2*ddq_dec_i*(q_i - q_min_i)))))");

  const std::pair<const char*, const char*> pairs[] = {{"docs_2025_10", "docs_2025_10_current"},
                                                       {"libfranka_0_15", "libfranka_hardcoded_and_test_urdf"}};
  for (const auto& [name, data_name] : pairs) {
    SCOPED_TRACE(name);
    const JointLimits limits = fr3_limits(name);
    const json& set = fr3_velocity_limit().at("parameter_sets").at(data_name);
    const Vector7 q_min = v7(set.at("q_min")), q_max = v7(set.at("q_max")), dq_max = v7(set.at("dq_max"));
    const Vector7 offset = v7(set.at("dq_offset")), dec = v7(set.at("ddq_dec"));

    const auto check = [&](const Vector7& q) {
      const Vector7 upper = limits.dq_upper(q), lower = limits.dq_lower(q);
      for (int i = 0; i < kNumJoints; ++i) {
        EXPECT_NEAR(upper[i], upper_formula(q[i], q_max[i], dq_max[i], offset[i], dec[i]), 1e-12)
            << "joint " << i + 1 << " q " << q[i];
        EXPECT_NEAR(lower[i], lower_formula(q[i], q_min[i], dq_max[i], offset[i], dec[i]), 1e-12)
            << "joint " << i + 1 << " q " << q[i];
      }
    };
    // Random positions over the range and a little beyond it.
    std::mt19937_64 engine(20251014);
    for (int sample = 0; sample < 500; ++sample) {
      Vector7 q;
      for (int i = 0; i < kNumJoints; ++i)
        q[i] = std::uniform_real_distribution<double>(q_min[i] - 0.2, q_max[i] + 0.2)(engine);
      check(q);
    }
    // Near the limits, where the square root bites.
    for (const double distance : {0.0, 1e-9, 1e-6, 1e-4, 1e-3, 0.01, 0.02, 0.05, 0.1, 0.3, 1.0}) {
      check(q_max - Vector7::Constant(distance));
      check(q_min + Vector7::Constant(distance));
      check(q_max + Vector7::Constant(distance));
      check(q_min - Vector7::Constant(distance));
    }

    for (int i = 0; i < kNumJoints; ++i) {
      SCOPED_TRACE("joint " + std::to_string(i + 1));
      ASSERT_GT(offset[i], 0.0);
      // Zero at the position limit and beyond it, in the direction of the limit.
      EXPECT_EQ(limits.dq_upper(q_max)[i], 0.0);
      EXPECT_EQ(limits.dq_lower(q_min)[i], 0.0);
      EXPECT_EQ(limits.dq_upper(q_max + Vector7::Constant(0.1))[i], 0.0);
      EXPECT_EQ(limits.dq_lower(q_min - Vector7::Constant(0.1))[i], 0.0);
      // With dq_offset > 0 the limit reaches zero dq_offset^2 / (2 ddq_dec) before the position limit.
      const double margin = offset[i] * offset[i] / (2.0 * dec[i]);
      EXPECT_EQ(limits.dq_upper(q_max - Vector7::Constant(0.999 * margin))[i], 0.0);
      EXPECT_GT(limits.dq_upper(q_max - Vector7::Constant(1.001 * margin))[i], 0.0);
      EXPECT_EQ(limits.dq_lower(q_min + Vector7::Constant(0.999 * margin))[i], 0.0);
      EXPECT_LT(limits.dq_lower(q_min + Vector7::Constant(1.001 * margin))[i], 0.0);
      // Mid-range: the constant cap, both ways (every FR3 joint brakes from dq_max within its range).
      const Vector7 middle = 0.5 * (q_min + q_max);
      EXPECT_EQ(limits.dq_upper(middle)[i], dq_max[i]);
      EXPECT_EQ(limits.dq_lower(middle)[i], -dq_max[i]);
      // Moving away from a limit is never restricted by it: full speed away at the limit itself.
      EXPECT_EQ(limits.dq_lower(q_max)[i], -dq_max[i]);
      EXPECT_EQ(limits.dq_upper(q_min)[i], dq_max[i]);
    }
  }
}

TEST(ConfigVelocityLimits, Fr3SetsAreSelectableAndDiffer) {
  EXPECT_EQ(fr3_limits("").q_max, fr3_limits("docs_2025_10").q_max);   // the default
  const JointLimits docs = fr3_limits("docs_2025_10"), libfranka = fr3_limits("libfranka_0_15");
  EXPECT_NE(docs.q_max, libfranka.q_max);
  EXPECT_NE(docs.dq_offset, libfranka.dq_offset);
  // The data file's example: the joint-1 zero-velocity point is 2.8644 (docs) vs 2.7426 (libfranka).
  const auto zero_point = [](const JointLimits& l) {
    return l.q_max[0] - l.dq_offset[0] * l.dq_offset[0] / (2.0 * l.ddq_dec[0]);
  };
  EXPECT_NEAR(zero_point(docs), 2.8644, 5e-5);
  EXPECT_NEAR(zero_point(libfranka), 2.7426, 5e-5);
  Vector7 q = Vector7::Zero();
  q[0] = 2.8;   // between the two: libfranka allows no positive velocity, the docs do
  EXPECT_EQ(libfranka.dq_upper(q)[0], 0.0);
  EXPECT_GT(docs.dq_upper(q)[0], 0.1);
}

TEST(ConfigVelocityLimits, PandaLimitsAreConstant) {
  const JointLimits limits = make_model("panda").parameters().joint_limits;
  const Vector7 dq_max = v7(data_file().at("limits").at("panda").at("joint").at("dq_max"));
  EXPECT_FALSE(limits.position_based_velocity);
  RandomStates random(7);
  std::vector<Vector7> positions = {limits.q_min, limits.q_max, limits.q_max + Vector7::Constant(0.5),
                                    limits.q_min - Vector7::Constant(0.5)};
  for (int i = 0; i < 200; ++i) positions.push_back(random.q(limits));
  for (const Vector7& q : positions) {
    EXPECT_TRUE(same(limits.dq_upper(q), dq_max));
    EXPECT_TRUE(same(limits.dq_lower(q), Vector7(-dq_max)));
  }
}

// ---------------------------------------------------------------------------------------------
// The per-sample limit check the emulator's reflexes and the planner's trajectory check share.

TEST(LimitViolations, JointPowerCountsOnlyTheJointsThatDrive) {
  const Vector7 tau = (Vector7() << 10.0, -20.0, 5.0, 0.0, 2.0, -1.0, 3.0).finished();
  const Vector7 dq = (Vector7() << 1.0, 0.5, -2.0, 7.0, 0.25, -4.0, 1.0).finished();
  // 10 + 0 (brakes) + 0 (brakes) + 0 + 0.5 + 4 + 3
  EXPECT_EQ(joint_power(tau, dq), 17.5);
}

TEST(LimitViolations, EachLimitHoldsAtItsBoundAndIsViolatedBeyondItsTolerance) {
  for (const std::string& robot : std::vector<std::string>{"panda", "fr3"}) {
    const JointLimits limits = make_model(robot).parameters().joint_limits;
    const Vector7 middle = 0.5 * (limits.q_min + limits.q_max);
    const Vector7 rest = Vector7::Zero();
    auto violated = [&](const Vector7& q, const Vector7& dq, const Vector7& tau, double power, double tolerance) {
      return limit_violations(limits, q, dq, tau, power, tolerance);
    };
    for (int j = 0; j < kNumJoints; ++j) {
      const Vector7 unit = Vector7::Unit(j);
      for (const double tolerance : {0.0, kLimitTolerance}) {
        const double beyond = tolerance + 1e-6;   // past the bound and its tolerance
        SCOPED_TRACE(robot + " joint " + std::to_string(j + 1) + " tolerance " + std::to_string(tolerance));
        // Position: at either bound, within tolerance; beyond it, only that joint.
        for (const double bound : {limits.q_min[j], limits.q_max[j]}) {
          Vector7 at = middle, past = middle;
          at[j] = bound;
          past[j] = bound > middle[j] ? bound + beyond : bound - beyond;
          EXPECT_TRUE(violated(at, rest, rest, 0.0, tolerance).position.none());
          EXPECT_EQ(violated(past, rest, rest, 0.0, tolerance).position, std::bitset<kNumJoints>().set(j));
        }
        // Velocity: against the bounds at that position (FR3: position-based).
        const Vector7 upper = limits.dq_upper(middle), lower = limits.dq_lower(middle);
        EXPECT_TRUE(violated(middle, upper[j] * unit, rest, 0.0, tolerance).velocity.none());
        EXPECT_TRUE(violated(middle, lower[j] * unit, rest, 0.0, tolerance).velocity.none());
        EXPECT_EQ(violated(middle, (upper[j] + beyond) * unit, rest, 0.0, tolerance).velocity,
                  std::bitset<kNumJoints>().set(j));
        EXPECT_EQ(violated(middle, (lower[j] - beyond) * unit, rest, 0.0, tolerance).velocity,
                  std::bitset<kNumJoints>().set(j));
        // Torque: |tau| against tau_max, either sign.
        for (const double sign : {1.0, -1.0}) {
          EXPECT_TRUE(violated(middle, rest, sign * limits.tau_max[j] * unit, 0.0, tolerance).torque.none());
          EXPECT_EQ(violated(middle, rest, sign * (limits.tau_max[j] + beyond) * unit, 0.0, tolerance).torque,
                    std::bitset<kNumJoints>().set(j));
        }
        // Power: the caller's number against power_max.
        EXPECT_FALSE(violated(middle, rest, rest, limits.power_max, tolerance).power);
        EXPECT_TRUE(violated(middle, rest, rest, limits.power_max + beyond, tolerance).power);
      }
    }
    // Within the tolerance is no violation; the exact check (0) sees it.
    Vector7 just_over = middle;
    just_over[0] = limits.q_max[0] + 0.5 * kLimitTolerance;
    EXPECT_TRUE(violated(just_over, rest, rest, 0.0, kLimitTolerance).position.none());
    EXPECT_TRUE(violated(just_over, rest, rest, 0.0, 0.0).position.test(0));
  }
}

// FR3's velocity bound shrinks to zero at the position limit: a joint there may only move back.
TEST(LimitViolations, Fr3VelocityBoundIsThePositionsOne) {
  const JointLimits limits = make_model("fr3").parameters().joint_limits;
  ASSERT_TRUE(limits.position_based_velocity);
  const Vector7 at_upper = limits.q_max, rest = Vector7::Zero();
  const Vector7 outward = 1e-3 * Vector7::Unit(3), inward = -1e-3 * Vector7::Unit(3);
  EXPECT_TRUE(limit_violations(limits, at_upper, outward, rest, 0.0, kLimitTolerance).velocity.test(3));
  EXPECT_TRUE(limit_violations(limits, at_upper, inward, rest, 0.0, kLimitTolerance).velocity.none());
}

// ---------------------------------------------------------------------------------------------
// Validation: each rule rejects a broken copy of panda.yaml with a message naming the file, the
// key path and what was expected.

// One text edit: replace the first `from` after the first `after` (from the start if empty).
struct Edit {
  std::string from, to, after = "";
};

// A robot file with the edits applied in order. An edit whose text is not found throws, so a
// change to the robot file makes these tests fail loudly instead of testing nothing.
std::string edited(const std::string& robot, std::initializer_list<Edit> edits) {
  std::string text = read_text(robot_file(robot));
  for (const Edit& edit : edits) {
    const std::size_t start = edit.after.empty() ? 0 : text.find(edit.after);
    if (start == std::string::npos) throw std::runtime_error(robot + ".yaml no longer contains `" + edit.after + "`");
    const std::size_t at = text.find(edit.from, start);
    if (at == std::string::npos)
      throw std::runtime_error(robot + ".yaml no longer contains `" + edit.from + "` after `" + edit.after + "`");
    text.replace(at, edit.from.size(), edit.to);
  }
  return text;
}

std::string edited_panda(std::initializer_list<Edit> edits) { return edited("panda", edits); }

// The test's own file name, so each broken file is told apart in a message.
std::string test_file_name() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return std::string(info->test_suite_name()) + "_" + info->name() + ".yaml";
}

// The ConfigError message of loading `text` (written to a temp file at `path`), or a failure.
std::string load_error_at(const std::string& path) {
  try {
    load_robot_config(path);
  } catch (const ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ConfigError, got another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected ConfigError, but " << path << " loaded";
  return "";
}

// Loads the edited panda.yaml and checks the message names the file and contains every fragment
// (the key path and what was expected). Returns the message for further checks.
std::string expect_rejected_in(const std::string& robot, std::initializer_list<Edit> edits,
                               std::initializer_list<std::string> fragments, const std::string& file_name) {
  const std::string path = write_temp(file_name, edited(robot, edits));
  const std::string message = load_error_at(path);
  EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << "message does not start with the file: " << message;
  for (const std::string& fragment : fragments)
    EXPECT_NE(message.find(fragment), std::string::npos) << "`" << fragment << "` not in: " << message;
  EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 0) << "one line expected: " << message;
  return message;
}

std::string expect_rejected(std::initializer_list<Edit> edits, std::initializer_list<std::string> fragments,
                            const std::string& file_name = test_file_name()) {
  return expect_rejected_in("panda", edits, fragments, file_name);
}

TEST(ConfigValidation, UnchangedCopyLoads) {
  // The baseline of every test below: the copy itself is fine, only the edit breaks it.
  const std::string path = write_temp(test_file_name(), edited_panda({}));
  EXPECT_NO_THROW(load_robot_config(path));
}

TEST(ConfigValidation, MissingKey) {
  expect_rejected({{"    elbow: {v_max: 2.175, a_max: 10.0, j_max: 5000.0}\n", ""}},
                  {"limits.cartesian.elbow: expected this key (missing)"}, "missing_elbow.yaml");
  expect_rejected({{"name: panda\n", ""}}, {": name: expected this key (missing)"}, "missing_name.yaml");
  // `physical` has no default either.
  expect_rejected({{"      physical: true\n", "", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.physical: expected this key (missing)"}, "missing_physical.yaml");
  expect_rejected({{"com: [0.027518, 0.039252, -0.066502], ", "", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.links[2].com: expected this key (missing)"}, "missing_com.yaml");
  expect_rejected({{"  default: gaz2019\n", "", "\nfriction:\n"}}, {"friction.default: expected this key (missing)"},
                  "missing_friction_default.yaml");
  expect_rejected({{"        tau_max: [87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0]\n", ""}},
                  {"limits.joint.sets.franka_docs.tau_max: expected this key (missing)"}, "missing_tau_max.yaml");
}

TEST(ConfigValidation, UnknownKeyIsATypoNotADefault) {
  expect_rejected({{"dddq_max:", "dddq_maxx:"}},
                  {"limits.joint.sets.franka_docs.dddq_maxx: expected no such key", "allowed:", "dddq_max"},
                  "typo_dddq_max.yaml");
  expect_rejected({{"theta_offset: 0.0}", "theta_ofset: 0.0}"}},
                  {"kinematics.mdh[0].theta_ofset: expected no such key", "theta_offset"}, "typo_theta_offset.yaml");
  expect_rejected({{"\nfriction:\n", "\nfrictions:\n"}}, {": frictions: expected no such key", "friction"},
                  "typo_friction.yaml");
  expect_rejected({{"    F_T_EE:", "    F_T_EE_:"}}, {"end_effectors.hand.F_T_EE_: expected no such key", "F_T_EE"},
                  "typo_F_T_EE.yaml");
  // An extra key next to the right one is rejected too.
  expect_rejected({{"    elbow:", "    shoulder: {v_max: 1.0, a_max: 1.0, j_max: 1.0}\n    elbow:"}},
                  {"limits.cartesian.shoulder: expected no such key"}, "extra_shoulder.yaml");
}

TEST(ConfigValidation, WrongArrayLength) {
  expect_rejected({{"q_min: [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]",
                    "q_min: [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175]"}},
                  {"limits.joint.sets.franka_docs.q_min: expected a list of 7 numbers"}, "short_q_min.yaml");
  expect_rejected({{"dtau_max: [1000.0,", "dtau_max: [1000.0, 1000.0,"}},
                  {"limits.joint.sets.franka_docs.dtau_max: expected a list of 7 numbers"}, "long_dtau_max.yaml");
  expect_rejected({{"com: [-0.01, 0.0, 0.03]", "com: [-0.01, 0.0]"}},
                  {"end_effectors.hand.com: expected a list of 3 numbers"}, "short_hand_com.yaml");
  expect_rejected({{"translation: [0.0, 0.0, 0.1034]", "translation: [0.0, 0.0, 0.1034, 0.0]"}},
                  {"end_effectors.hand.F_T_EE.translation: expected a list of 3 numbers"}, "long_tcp.yaml");
  expect_rejected({{"inertia: [0.70337, -0.000139, 0.006772, 0.70661, 0.019169, 0.009117]",
                    "inertia: [0.70337, -0.000139, 0.006772, 0.70661, 0.019169]", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.links[0].inertia: expected a list of 6 numbers"}, "short_inertia.yaml");
  expect_rejected({{"phi1: [0.54615,", "phi1: ["}}, {"friction.sets.gaz2019.phi1: expected a list of 7 numbers"},
                  "short_phi1.yaml");
  // Lists of rows: 6 MDH rows, 8 links.
  expect_rejected({{"    - {a: 0.088, d: 0.0, alpha: 1.5707963267948966, theta_offset: 0.0}", "#"}},
                  {"kinematics.mdh: expected 7 rows"}, "six_mdh_rows.yaml");
  expect_rejected({{"      links:\n", "      links:\n        - {mass: 1.0, com: [0.0, 0.0, 0.0], "
                                     "inertia: [0.1, 0.0, 0.0, 0.1, 0.0, 0.1]}\n", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.links: expected 7 links"}, "eight_links.yaml");
  // A scalar where a list is expected.
  expect_rejected({{"dq_max: [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]", "dq_max: 2.175"}},
                  {"limits.joint.sets.franka_docs.dq_max: expected a list of 7 numbers"}, "scalar_dq_max.yaml");
}

TEST(ConfigValidation, NonNumber) {
  expect_rejected({{"mass: 0.73", "mass: heavy"}}, {"end_effectors.hand.mass: expected a number"},
                  "text_mass.yaml");
  expect_rejected({{"dq_max: [2.175,", "dq_max: [fast,"}},
                  {"limits.joint.sets.franka_docs.dq_max[0]: expected a number"},
                  "text_dq_max.yaml");
  expect_rejected({{"translation: {v_max: 1.7,", "translation: {v_max: [1.7],"}},
                  {"limits.cartesian.translation.v_max: expected a number"}, "list_v_max.yaml");
  expect_rejected({{"  flange: {a: 0.0, d: 0.107, alpha: 0.0}", "  flange: {a: 0.0, d: , alpha: 0.0}"}},
                  {"kinematics.flange.d: expected a number"}, "empty_flange_d.yaml");
}

TEST(ConfigValidation, NonFiniteNumber) {
  expect_rejected({{"com: [0.027518, 0.039252, -0.066502]", "com: [0.027518, .nan, -0.066502]", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.links[2].com[1]: expected a finite number"}, "nan_com.yaml");
  expect_rejected({{"translation: {v_max: 1.7,", "translation: {v_max: .inf,"}},
                  {"limits.cartesian.translation.v_max: expected a finite number"}, "inf_v_max.yaml");
  expect_rejected({{"q_min: [-2.8973,", "q_min: [-.inf,"}},
                  {"limits.joint.sets.franka_docs.q_min[0]: expected a finite number"}, "minus_inf_q_min.yaml");
  expect_rejected({{"{a: 0.0825, d: 0.0,", "{a: .NaN, d: 0.0,"}}, {"kinematics.mdh[3].a: expected a finite number"},
                  "nan_mdh.yaml");
  expect_rejected({{"phi3: [0.039533,", "phi3: [.Inf,"}}, {"friction.sets.gaz2019.phi3[0]: expected a finite number"},
                  "inf_phi3.yaml");
  expect_rejected({{"mass: 0.73", "mass: .nan"}}, {"end_effectors.hand.mass: expected a finite number"},
                  "nan_hand_mass.yaml");
}

TEST(ConfigValidation, PositionLimitsMustBeOrdered) {
  // Joint 4: q_min = -3.0718, q_max = -0.0698. Equal bounds are rejected ...
  expect_rejected({{"-0.0698, 2.8973", "-3.0718, 2.8973"}},
                  {"limits.joint.sets.franka_docs.q_max: expected q_min < q_max for every joint", "joint 4"},
                  "equal_q_joint4.yaml");
  // ... and so are swapped ones.
  expect_rejected({{"q_min: [-2.8973,", "q_min: [3.5,"}},
                  {"limits.joint.sets.franka_docs.q_max: expected q_min < q_max", "joint 1"}, "swapped_q_joint1.yaml");
}

TEST(ConfigValidation, OtherLimitsMustBePositive) {
  expect_rejected({{"tau_max: [87.0,", "tau_max: [0.0,"}},
                  {"limits.joint.sets.franka_docs.tau_max: expected 7 positive numbers"}, "zero_tau_max.yaml");
  expect_rejected({{"ddq_max: [15.0, 7.5,", "ddq_max: [15.0, -7.5,"}},
                  {"limits.joint.sets.franka_docs.ddq_max: expected 7 positive numbers"}, "negative_ddq_max.yaml");
  expect_rejected({{"rotation: {v_max: 2.5, a_max: 25.0,", "rotation: {v_max: 2.5, a_max: -25.0,"}},
                  {"limits.cartesian.rotation: expected positive v_max, a_max, j_max"}, "negative_a_max.yaml");
}

TEST(ConfigValidation, PowerLimitIsTheDefaultUnlessTheSetGivesAPositiveOne) {
  EXPECT_EQ(make_model("panda").parameters().joint_limits.power_max, kDefaultPowerMax);
  EXPECT_EQ(make_model("fr3").parameters().joint_limits.power_max, kDefaultPowerMax);
  const std::string dtau = "dtau_max: [1000.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0]";
  const std::string path = write_temp(test_file_name(), edited_panda({{dtau, dtau + "\n        power_max: 65.0"}}));
  EXPECT_EQ(model_parameters(load_robot_config(path), {}).joint_limits.power_max, 65.0);
  expect_rejected({{dtau, dtau + "\n        power_max: 0.0"}},
                  {"limits.joint.sets.franka_docs.power_max: expected a positive number"}, "zero_power_max.yaml");
}

TEST(ConfigValidation, MassMustBePositive) {
  // Link 3 of franka_ros_urdf: zero mass; link 3 of gaz2019: negative mass.
  expect_rejected({{"mass: 3.228604", "mass: 0.0", "franka_ros_urdf:"}},
                  {"inertia.sets.franka_ros_urdf.links[2].mass: expected a positive mass"}, "zero_link_mass.yaml");
  expect_rejected({{"mass: 3.228604", "mass: -3.228604", "\ninertia:\n"}},
                  {"inertia.sets.gaz2019.links[2].mass: expected a positive mass"}, "negative_link_mass.yaml");
  // Even in a set that is not physical.
  expect_rejected({{"mass: 4.970684", "mass: -4.970684", "libfranka_fit:"}},
                  {"inertia.sets.libfranka_fit.links[0].mass: expected a positive mass"},
                  "negative_mass_not_physical.yaml");
  // The end effector may be massless but not negative.
  expect_rejected({{"mass: 0.73", "mass: -0.73"}}, {"end_effectors.hand.mass: expected a non-negative mass"},
                  "negative_hand_mass.yaml");
}

TEST(ConfigValidation, PositionBasedVelocityParameters) {
  const std::string key = "limits.joint.sets.docs_2025_10.position_based_velocity.";
  expect_rejected_in("fr3", {{"dq_offset: [0.6599,", "dq_offset: [-0.6599,"}},
                     {key + "dq_offset: expected 7 non-negative numbers"}, "fr3_negative_offset.yaml");
  expect_rejected_in("fr3", {{"ddq_dec: [6.0,", "ddq_dec: [0.0,"}}, {key + "ddq_dec: expected 7 positive numbers"},
                     "fr3_zero_ddq_dec.yaml");
  expect_rejected_in("fr3", {{"ddq_dec: [6.0,", "ddq_dec: [6.0, 6.0,"}},
                     {key + "ddq_dec: expected a list of 7 numbers"},
                     "fr3_long_ddq_dec.yaml");
  expect_rejected_in("fr3", {{"ddq_dec:", "ddq_decel:"}}, {key + "ddq_decel: expected no such key", "ddq_dec"},
                     "fr3_typo_ddq_dec.yaml");
  expect_rejected_in("fr3", {{", ddq_dec: [6.0, 2.585, 3.5, 4.0, 17.0, 5.5, 17.0]", ""}},
                     {key + "ddq_dec: expected this key (missing)"}, "fr3_missing_ddq_dec.yaml");
  // A zero offset is allowed (the limit then reaches zero exactly at q_max).
  const std::string path =
      write_temp("fr3_zero_offset.yaml", edited("fr3", {{"dq_offset: [0.6599,", "dq_offset: [0.0,"}}));
  const JointLimits limits = load_robot_config(path).joint_limits.at("docs_2025_10");
  EXPECT_EQ(limits.dq_offset[0], 0.0);
  EXPECT_EQ(limits.dq_upper(limits.q_max)[0], 0.0);
  EXPECT_GT(limits.dq_upper(limits.q_max - Vector7::Constant(1e-4))[0], 0.0);
}

// Link 2 inertias: one with a negative principal moment, one positive definite but violating the
// triangle inequality (0.01 > 0.001 + 0.001).
const std::string kLink2Inertia = "inertia: [0.007962, -0.003925, 0.010254, 0.02811, 0.000704, 0.025995]";
const std::string kNotPositiveDefinite = "inertia: [0.01, 0.0, 0.0, 0.01, 0.0, -0.001]";
const std::string kNotTriangle = "inertia: [0.001, 0.0, 0.0, 0.001, 0.0, 0.01]";

TEST(ConfigValidation, PhysicalSetNeedsPositiveDefiniteInertia) {
  expect_rejected({{kLink2Inertia, kNotPositiveDefinite, "franka_ros_urdf:"}},
                  {"inertia.sets.franka_ros_urdf.links[1].inertia: expected a positive-definite inertia",
                   "physical: false"},
                  "not_positive_definite.yaml");
  // Indefinite off-diagonal terms too: eigenvalues 0.03 and -0.01.
  expect_rejected({{kLink2Inertia, "inertia: [0.01, 0.02, 0.0, 0.01, 0.0, 0.01]", "franka_ros_urdf:"}},
                  {"inertia.sets.franka_ros_urdf.links[1].inertia: expected a positive-definite inertia"},
                  "indefinite.yaml");
}

TEST(ConfigValidation, PhysicalSetNeedsTriangleInequality) {
  expect_rejected({{kLink2Inertia, kNotTriangle, "franka_ros_urdf:"}},
                  {"inertia.sets.franka_ros_urdf.links[1].inertia: expected", "triangle inequality"},
                  "not_triangle.yaml");
  EXPECT_FALSE(is_physical_inertia(Vector3(0.001, 0.001, 0.01).asDiagonal()));
  EXPECT_TRUE(is_physical_inertia(Vector3(0.001, 0.001, 0.002).asDiagonal()));   // the boundary: a flat plate
  EXPECT_FALSE(is_physical_inertia(Vector3(0.01, 0.01, -0.001).asDiagonal()));
  EXPECT_FALSE(is_physical_inertia(Matrix3::Zero()));
}

TEST(ConfigValidation, SameInertiaAcceptedWhenSetIsNotPhysical) {
  const std::string path = write_temp(
      test_file_name(), edited_panda({{"physical: true", "physical: false", "franka_ros_urdf:"},
                                      {kLink2Inertia, kNotPositiveDefinite, "franka_ros_urdf:"},
                                      {"inertia: [0.037242, -0.004761, -0.011396, 0.036155, -0.012805, 0.01083]",
                                       kNotTriangle, "franka_ros_urdf:"}}));
  RobotConfig config;
  ASSERT_NO_THROW(config = load_robot_config(path));
  const InertiaSet& set = config.inertia_sets.at("franka_ros_urdf");
  EXPECT_FALSE(set.physical);
  EXPECT_TRUE(same(set.links[1].inertia, Matrix3(Vector3(0.01, 0.01, -0.001).asDiagonal())));
  EXPECT_TRUE(same(set.links[2].inertia, Matrix3(Vector3(0.001, 0.001, 0.01).asDiagonal())));
  // The flag reaches the model parameters, so callers can refuse the set where physics is needed.
  ModelOptions options;
  options.inertia = "franka_ros_urdf";
  EXPECT_FALSE(model_parameters(config, options).physically_consistent);
  EXPECT_TRUE(model_parameters(config, {}).physically_consistent);   // gaz2019 is untouched
}

TEST(ConfigValidation, UnknownDefaultName) {
  expect_rejected({{"default: gaz2019", "default: gaz2020", "\ninertia:\n"}},
                  {"inertia.default: expected the name of one of the sets"}, "unknown_inertia_default.yaml");
  expect_rejected({{"default: franka_docs", "default: franka_doc"}},
                  {"limits.joint.default: expected the name of one of the sets"}, "unknown_limits_default.yaml");
  expect_rejected({{"default: gaz2019", "default: gaz", "\nfriction:\n"}},
                  {"friction.default: expected the name of one of the sets"}, "unknown_friction_default.yaml");
  // `none` is built in for friction (the FR3 file uses it), not for inertia or limits.
  const std::string path = write_temp("friction_default_none.yaml",
                                      edited_panda({{"default: gaz2019", "default: none", "\nfriction:\n"}}));
  EXPECT_EQ(load_robot_config(path).default_friction, "none");
  expect_rejected({{"default: gaz2019", "default: none", "\ninertia:\n"}},
                  {"inertia.default: expected the name of one of the sets"}, "inertia_default_none.yaml");
}

TEST(ConfigValidation, BuiltInNamesCannotBeRedefined) {
  expect_rejected({{"  hand:", "  none:"}}, {"end_effectors.none: expected another name"}, "ee_named_none.yaml");
  expect_rejected({{"    gaz2019_linear_osi:", "    none:"}}, {"friction.sets.none: expected another name"},
                  "friction_named_none.yaml");
}

TEST(ConfigValidation, UnknownFrictionType) {
  expect_rejected({{"type: gaz_sigmoid", "type: coulomb"}},
                  {"friction.sets.gaz2019.type: expected gaz_sigmoid or linear"}, "unknown_friction_type.yaml");
  // A known type with the other type's keys is an unknown key, not a silent zero.
  expect_rejected({{"type: gaz_sigmoid", "type: linear"}}, {"friction.sets.gaz2019.phi1: expected no such key"},
                  "sigmoid_keys_in_linear.yaml");
}

TEST(ConfigValidation, StaticFrictionValues) {
  const std::string block = "friction.sets.gaz2019.static_friction.";
  expect_rejected({{"breakaway: [0.245,", "breakaway: [-0.245,"}}, {block + "breakaway: expected 7 numbers from 0 to 100 N m"},
                  "negative_breakaway.yaml");
  expect_rejected({{"breakaway: [0.245,", "breakaway: [1e5,"}}, {block + "breakaway: expected 7 numbers from 0 to 100 N m"},
                  "huge_breakaway.yaml");
  expect_rejected({{"stribeck_velocity: [0.05,", "stribeck_velocity: [0.0,"}},
                  {block + "stribeck_velocity: expected 7 positive numbers"}, "zero_stribeck_velocity.yaml");
  expect_rejected({{"stribeck_velocity: [0.05,", "stribeck_velocity: [50.0,"}},
                  {block + "stribeck_velocity: expected 7 positive numbers of at most 10 rad/s"}, "fast_stribeck_velocity.yaml");
  expect_rejected({{"stribeck_velocity: [0.05", "stribeck_speed: [0.05"}}, {block + "stribeck_speed: expected no such key"},
                  "misspelt_stribeck_velocity.yaml");
  // What loads is what the file says.
  ModelOptions options;
  options.friction = "gaz2019";
  const Vector7 breakaway = model_parameters(load_robot_config(robot_file("panda")), options).friction.breakaway;
  EXPECT_EQ(breakaway, (Vector7() << 0.245, 0.1523, 0.1827, 0.3591, 0.2669, 0.1658, 0.2109).finished());
}

TEST(ConfigValidation, ArmatureValues) {
  auto with = [](const std::string& armature) { return Edit{"name: panda\n", "name: panda\narmature: " + armature + "\n"}; };
  expect_rejected({with("{values: [0.1, 0.1, 0.1, -0.1, 0.1, 0.1, 0.1], source: x}")},
                  {"armature.values: expected 7 non-negative numbers"}, "negative_armature.yaml");
  expect_rejected({with("{values: [0.1, 0.1, 0.1], source: x}")}, {"armature.values: expected a list of 7 numbers"},
                  "short_armature.yaml");
  expect_rejected({with("{values: [0.1, 0.1, 0.1, .nan, 0.1, 0.1, 0.1], source: x}")},
                  {"armature.values[3]: expected a finite number"}, "nan_armature.yaml");
  expect_rejected({with("{values: [0.1, 0.1, 0.1, 1e200, 0.1, 0.1, 0.1], source: x}")},
                  {"armature.values: expected 7 rotor inertias of at most 1000 kg m^2"}, "huge_armature.yaml");
  expect_rejected({with("{values: [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]}")}, {"armature.source: expected this key (missing)"},
                  "armature_without_source.yaml");
  expect_rejected({with("{values: [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1], source: x, joints: 7}")},
                  {"armature.joints: expected no such key"}, "armature_unknown_key.yaml");
  // What loads is what the file says.
  const std::string path = write_temp("armature.yaml", edited_panda({with("{values: [0.4, 0.4, 0.3, 0.3, 0.1, 0.1, 0.05], source: x}")}));
  EXPECT_EQ(load_robot_config(path).armature.values, (Vector7() << 0.4, 0.4, 0.3, 0.3, 0.1, 0.1, 0.05).finished());
}

TEST(ConfigValidation, UnreadableFile) {
  const std::string missing = (temp_dir() / "no_such_robot.yaml").string();
  const std::string message = load_error_at(missing);
  EXPECT_NE(message.find(missing + ": cannot open"), std::string::npos) << message;

  const std::string empty = write_temp("empty.yaml", "");
  const std::string empty_message = load_error_at(empty);
  EXPECT_NE(empty_message.find(empty + ": top level: expected a mapping"), std::string::npos) << empty_message;
}

// A path that exists but is not a readable file is a ConfigError naming it, like a missing one.
TEST(ConfigValidation, DirectoryIsNotARobotFile) {
  const std::string directory = temp_dir().string();
  const std::string message = load_error_at(directory);
  EXPECT_NE(message.find(directory + ": "), std::string::npos) << message;
}

// The 1-based line of panda.yaml where `text` starts, and the line number a message reports.
long line_of(const std::string& text) {
  const std::string original = read_text(robot_file("panda"));
  const std::size_t at = original.find(text);
  if (at == std::string::npos) throw std::runtime_error("panda.yaml no longer contains `" + text + "`");
  return std::count(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(at), '\n') + 1;
}
long reported_line(const std::string& message) {
  const std::size_t at = message.find("(line ");
  return at == std::string::npos ? -1 : std::stol(message.substr(at + 6));
}

TEST(ConfigValidation, InvalidYaml) {
  // An unclosed bracket: yaml-cpp notices it at the end of that line, so on the line or the next.
  const std::string flange = "  flange: {a: 0.0, d: 0.107, alpha: 0.0}";
  const std::string unclosed =
      expect_rejected({{flange, "  flange: {a: 0.0, d: [0.107"}}, {"not valid YAML", "(line "}, "unclosed.yaml");
  EXPECT_GE(reported_line(unclosed), line_of(flange)) << unclosed;
  EXPECT_LE(reported_line(unclosed), line_of(flange) + 1) << unclosed;

  // A mapping value where none may be: the line itself.
  const std::string twice = expect_rejected({{"name: panda", "name: panda: arm"}}, {"not valid YAML", "(line "},
                                            "double_colon.yaml");
  EXPECT_EQ(reported_line(twice), line_of("name: panda")) << twice;

  // A tab in the indentation.
  expect_rejected({{"\n  flange:", "\n\tflange:"}}, {"not valid YAML"}, "tab.yaml");
}

// Finite but absurd numbers are named where they are written, not found later as a non-finite torque.
TEST(ConfigValidation, AbsurdMagnitudesAreRejected) {
  expect_rejected({{"{a: 0.0, d: 0.333, alpha: 0.0, theta_offset: 0.0}", "{a: 0.0, d: 1e200, alpha: 0.0, theta_offset: 0.0}"}},
                  {"kinematics", ".d: expected a length within +-10 m"}, "huge_length.yaml");
  expect_rejected({{"{a: 0.0, d: 0.333, alpha: 0.0, theta_offset: 0.0}", "{a: 0.0, d: 0.333, alpha: 1e9, theta_offset: 0.0}"}},
                  {".alpha: expected an angle within +-2 pi rad"}, "huge_angle.yaml");
}

// A key given twice would otherwise keep its first value silently (yaml-cpp looks keys up by
// their first occurrence); a second document would be ignored.
TEST(ConfigValidation, KeyGivenTwiceAndSecondDocumentAreRejected) {
  const std::string twice = expect_rejected({{"name: panda", "name: panda\nname: fr3"}}, {"name: key given twice", "(line "},
                                            "key_twice.yaml");
  EXPECT_EQ(reported_line(twice), line_of("name: panda") + 1) << twice;
  expect_rejected({{"  flange: {a: 0.0, d: 0.107, alpha: 0.0}", "  flange: {a: 0.0, d: 0.107, alpha: 0.0, d: 0.2}"}},
                  {"kinematics.flange.d: key given twice"}, "nested_key_twice.yaml");
  const std::string path = write_temp("two_documents.yaml", read_text(robot_file("panda")) + "\n---\nname: other\n");
  const std::string message = load_error_at(path);
  EXPECT_NE(message.find(path + ": expected one YAML document, found a second at line"), std::string::npos) << message;
  // A NUL in a key (found by csp_fuzz): yaml-cpp's own message then spans lines; CSP's stays one.
  std::string with_nul = read_text(robot_file("panda"));
  with_nul.replace(with_nul.find("sets:"), 5, std::string("sets\0", 5));
  const std::string nul_path = write_temp("nul.yaml", with_nul);
  const std::string nul_message = load_error_at(nul_path);
  EXPECT_EQ(std::count(nul_message.begin(), nul_message.end(), '\n'), 0) << nul_message;
  EXPECT_NE(nul_message.find(nul_path + ": "), std::string::npos) << nul_message;
  // yaml-cpp 0.7 loops forever on these (found by csp_fuzz): refused before it sees them.
  for (const char* text : {", x\n", "\"s\"\n, x\n", "--- , x\n", "name: x\n...\n, x\n", "&a , x\n"}) {
    const std::string hang = write_temp("hang.yaml", text);
    const std::string why = load_error_at(hang);
    EXPECT_NE(why.find(hang + ": expected"), std::string::npos) << why;
  }
}

// ---------------------------------------------------------------------------------------------
// Unknown set names in ModelOptions list what is available.

std::string options_error(const std::string& robot, const ModelOptions& options) {
  try {
    model_parameters(load_robot_config(robot_file(robot)), options);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected ConfigError";
  return "";
}

void expect_lists(const std::string& message, std::initializer_list<std::string> fragments) {
  for (const std::string& fragment : fragments)
    EXPECT_NE(message.find(fragment), std::string::npos) << "`" << fragment << "` not in: " << message;
}

TEST(ConfigOptions, UnknownSetNamesListTheAvailableOnes) {
  ModelOptions inertia;
  inertia.inertia = "gaz2020";
  expect_lists(options_error("panda", inertia),
               {robot_file("panda"), "inertial set", "`gaz2020`", "available:", "gaz2019", "franka_ros_urdf",
                "libfranka_fit"});
  ModelOptions friction;
  friction.friction = "coulomb";
  expect_lists(options_error("panda", friction), {"friction set", "`coulomb`", "available:", "none", "gaz2019",
                                                  "gaz2019_linear_cls", "gaz2019_linear_osi"});
  ModelOptions limits;
  limits.joint_limits = "franka_docs";   // a Panda set, not an FR3 one
  expect_lists(options_error("fr3", limits),
               {robot_file("fr3"), "joint limit set", "`franka_docs`", "available:", "docs_2025_10", "libfranka_0_15"});
  ModelOptions ee;
  ee.end_effector = "gripper";
  expect_lists(options_error("fr3", ee), {"end effector", "`gripper`", "available:", "none", "hand"});
}

// ---------------------------------------------------------------------------------------------
// The Model itself refuses a flange load it cannot represent.

TEST(ConfigModel, RejectsNegativeOrNonFiniteLoad) {
  const ModelParameters base = model_parameters(load_robot_config(robot_file("panda")), {});
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();

  const auto rejected = [&](const char* what, auto change) {
    SCOPED_TRACE(what);
    ModelParameters p = base;
    change(p);
    EXPECT_THROW(Model{p}, std::invalid_argument);
  };
  rejected("negative load mass", [](ModelParameters& p) { p.load.mass = -0.5; });
  rejected("NaN load mass", [&](ModelParameters& p) { p.load.mass = nan; });
  rejected("infinite load mass", [&](ModelParameters& p) { p.load.mass = inf; });
  rejected("NaN load CoM", [&](ModelParameters& p) { p.load = {1.0, Vector3(0.0, nan, 0.0), Matrix3::Zero()}; });
  rejected("infinite load inertia", [&](ModelParameters& p) {
    p.load.mass = 1.0;
    p.load.inertia(2, 2) = inf;
  });
  rejected("negative end-effector mass", [](ModelParameters& p) { p.end_effector.mass = -0.73; });
  rejected("NaN end-effector CoM", [&](ModelParameters& p) {
    p.end_effector.mass = 0.73;
    p.end_effector.com.x() = nan;
  });
  rejected("non-finite gravity", [&](ModelParameters& p) { p.gravity.z() = nan; });

  // Through ModelOptions and with_load as well.
  ModelOptions options;
  options.load = RigidBodyInertia{-1.0, Vector3::Zero(), Matrix3::Zero()};
  EXPECT_THROW(make_model("panda", options), std::invalid_argument);
  const Model model{base};
  EXPECT_THROW(with_load(model, {-1.0, Vector3::Zero(), Matrix3::Zero()}), std::invalid_argument);
  EXPECT_THROW(with_load(model, {1.0, Vector3::Constant(inf), Matrix3::Zero()}), std::invalid_argument);

  // A massless or a proper load is fine.
  EXPECT_NO_THROW(with_load(model, {0.0, Vector3::Zero(), Matrix3::Zero()}));
  EXPECT_NO_THROW(with_load(model, {0.5, Vector3(0.01, 0.02, 0.03), Matrix3(Vector3(1e-3, 1e-3, 1e-3).asDiagonal())}));
}

}  // namespace
}  // namespace csp::test
