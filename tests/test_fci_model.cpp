// The FCI model library (libcsp_fci_model.so, bridge/fci/model): the bytes model_library_for
// returns, written to a file and dlopened as libfranka does, called through libfranka's own
// declarations (the vendored libfcimodels.h), against CSP's dynamics computed directly, finite
// differences of the library's own poses, physical laws, and libfranka's model oracles.
#include <dlfcn.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "csp/dynamics/arrays.hpp"
#include "csp/fci/model_library.hpp"
#include "csp/fci/model_parameter_block.hpp"
#include "libfcimodels.h"   // libfranka 0.13.3's declarations of the model library's functions
#include "support.hpp"

namespace csp::test {
namespace {

using json = nlohmann::json;
using Matrix4 = Eigen::Matrix4d;

// libfranka's total load on the flange (m_total, F_x_Ctotal, I_total about the CoM).
struct TotalLoad {
  double mass = 0.0;
  Vector3 com = Vector3::Zero();
  Matrix3 inertia = Matrix3::Zero();
};

// One dlopened model library, its functions looked up by libfranka's names and called with
// libfranka's signatures (decltype of the vendored declarations).
class FciModelLibrary {
 public:
  explicit FciModelLibrary(const std::string& path) : handle_(::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) {
    if (handle_ == nullptr) throw std::runtime_error("dlopen " + path + ": " + ::dlerror());
  }
  ~FciModelLibrary() { ::dlclose(handle_); }
  FciModelLibrary(const FciModelLibrary&) = delete;
  FciModelLibrary& operator=(const FciModelLibrary&) = delete;

  template <typename Function>
  Function function(const std::string& name) const {
    void* symbol = ::dlsym(handle_, name.c_str());
    if (symbol == nullptr) throw std::runtime_error("no symbol " + name);
    return reinterpret_cast<Function>(symbol);
  }

  // Frame 1..9 (joints 1-7, flange, end effector with F_T_EE), as libfranka's Model calls them.
  Matrix4 pose(int frame, const Vector7& q, const Matrix4& F_T_EE = Matrix4::Identity()) const {
    Matrix4 O_T_frame;
    const std::string name = "O_T_J" + std::to_string(frame);
    if (frame == 9) function<decltype(&::O_T_J9)>(name)(q.data(), F_T_EE.data(), O_T_frame.data());
    else function<decltype(&::O_T_J1)>(name)(q.data(), O_T_frame.data());
    return O_T_frame;
  }
  Matrix6x7 zero_jacobian(int frame, const Vector7& q, const Matrix4& F_T_EE = Matrix4::Identity()) const {
    return jacobian("O_J_J", frame, q, F_T_EE);
  }
  Matrix6x7 body_jacobian(int frame, const Vector7& q, const Matrix4& F_T_EE = Matrix4::Identity()) const {
    return jacobian("Ji_J_J", frame, q, F_T_EE);
  }
  Matrix7 mass(const Vector7& q, const TotalLoad& load) const {
    Matrix7 M;
    function<decltype(&::M_NE)>("M_NE")(q.data(), load.inertia.data(), load.mass, load.com.data(), M.data());
    return M;
  }
  Vector7 coriolis(const Vector7& q, const Vector7& dq, const TotalLoad& load) const {
    Vector7 c;
    function<decltype(&::c_NE)>("c_NE")(q.data(), dq.data(), load.inertia.data(), load.mass, load.com.data(), c.data());
    return c;
  }
  Vector7 gravity(const Vector7& q, const TotalLoad& load, const Vector3& g_earth) const {
    Vector7 g;
    function<decltype(&::g_NE)>("g_NE")(q.data(), g_earth.data(), load.mass, load.com.data(), g.data());
    return g;
  }

 private:
  Matrix6x7 jacobian(const std::string& kind, int frame, const Vector7& q, const Matrix4& F_T_EE) const {
    Matrix6x7 J;
    const std::string name = kind + std::to_string(frame);
    if (frame == 1) function<decltype(&::O_J_J1)>(name)(J.data());   // constant: no q
    else if (frame == 9) function<decltype(&::O_J_J9)>(name)(q.data(), F_T_EE.data(), J.data());
    else function<decltype(&::O_J_J2)>(name)(q.data(), J.data());
    return J;
  }
  void* handle_;
};

// The robot models the server sends: the Panda's internal model (libfranka_fit, as the scenarios'
// robot_model) and the FR3's.
ModelParameters robot_parameters(const std::string& robot, const std::string& inertia = "") {
  ModelOptions options;
  options.inertia = inertia;
  options.end_effector = "hand";   // the block leaves it out: libfranka sends its total load per call
  return model_parameters(load_robot_config(robot_file(robot)), options);
}

// model_library_for's bytes in a file of its own, as libfranka writes them (a new file each time:
// rewriting a file a loaded library maps would change that library under it).
std::string library_file(const ModelParameters& robot_model, const std::string& name) {
  static int count = 0;
  const std::vector<std::uint8_t> bytes = fci::model_library_for(robot_model);
  return write_temp(name + "_" + std::to_string(count++) + ".so", std::string(bytes.begin(), bytes.end()));
}

// What the library must compute: the robot model with the call's total load, frame and gravity,
// and nothing else (no end effector, armature or friction).
Model reference_model(const ModelParameters& robot_model, const TotalLoad& load, const Matrix4& F_T_EE,
                      const Vector3& g_earth) {
  ModelParameters p;
  p.joints = robot_model.joints;
  p.link7_T_flange = robot_model.link7_T_flange;
  p.links = robot_model.links;
  p.load = {load.mass, load.com, load.inertia};
  p.F_T_EE = transform_from_matrix(F_T_EE);
  p.gravity = g_earth;
  return Model(p);
}

Matrix3 random_rotation(RandomStates& random) {
  const Vector3 axis = random.uniform(1.0).head<3>().normalized();
  return Eigen::AngleAxisd(random.uniform(M_PI)[0], axis).toRotationMatrix();
}

Matrix4 random_frame(RandomStates& random) {
  Matrix4 F_T_EE = Matrix4::Identity();
  F_T_EE.topLeftCorner<3, 3>() = random_rotation(random);
  F_T_EE.topRightCorner<3, 1>() = random.uniform(0.2).head<3>();
  return F_T_EE;
}

// A physical load: principal moments in [0.01, 0.02] kg m^2 (triangle inequality), rotated.
TotalLoad random_load(RandomStates& random) {
  const Matrix3 R = random_rotation(random);
  const Vector3 moments = (random.uniform(0.005).array() + 0.015).head<3>();
  return {1.5 + random.uniform(1.5)[0], random.uniform(0.1).head<3>(), R * moments.asDiagonal() * R.transpose()};
}

// The rotation vector of a small rotation matrix's derivative: (dR R^T) is skew, its axial vector.
Vector3 axial(const Matrix3& skew_matrix) {
  return 0.5 * Vector3(skew_matrix(2, 1) - skew_matrix(1, 2), skew_matrix(0, 2) - skew_matrix(2, 0),
                       skew_matrix(1, 0) - skew_matrix(0, 1));
}

// The zero Jacobian of a frame by central differences of the library's own pose of it.
Matrix6x7 finite_difference_jacobian(const FciModelLibrary& library, int frame, const Vector7& q,
                                     const Matrix4& F_T_EE) {
  constexpr double h = 1e-6;
  const Matrix3 R = library.pose(frame, q, F_T_EE).topLeftCorner<3, 3>();
  Matrix6x7 J;
  for (int j = 0; j < kNumJoints; ++j) {
    const Vector7 step = h * Vector7::Unit(j);
    const Matrix4 dT = (library.pose(frame, q + step, F_T_EE) - library.pose(frame, q - step, F_T_EE)) / (2 * h);
    J.col(j) << dT.topRightCorner<3, 1>(), axial(dT.topLeftCorner<3, 3>() * R.transpose());
  }
  return J;
}

// The potential energy of the links and the load in gravity g_earth, placed by the library's poses.
double potential_energy_of(const FciModelLibrary& library, const ModelParameters& robot_model, const Vector7& q,
                           const TotalLoad& load, const Vector3& g_earth) {
  double V = 0.0;
  for (int i = 0; i < kNumJoints; ++i) {
    const Matrix4 O_T_link = library.pose(i + 1, q);
    const Vector3 com = O_T_link.topLeftCorner<3, 3>() * robot_model.links[i].com + O_T_link.topRightCorner<3, 1>();
    V -= robot_model.links[i].mass * g_earth.dot(com);
  }
  const Matrix4 O_T_F = library.pose(8, q);
  V -= load.mass * g_earth.dot(O_T_F.topLeftCorner<3, 3>() * load.com + O_T_F.topRightCorner<3, 1>());
  return V;
}

class FciModel : public ::testing::TestWithParam<std::string> {
 protected:
  const ModelParameters robot_model = GetParam() == "panda" ? robot_parameters("panda", "libfranka_fit")
                                                            : robot_parameters(GetParam());
  const FciModelLibrary library{library_file(robot_model, "fci_model_" + GetParam())};
  RandomStates random{20261129};
  static constexpr int kStates = 20;
};

// (a) Every function against CSP's dynamics computed directly: FK and Jacobians of the frames, M
// by RNEA columns, c and g by RNEA, the load lumped on the flange.
TEST_P(FciModel, EveryFunctionIsCspDynamicsWithTheCallsLoadFrameAndGravity) {
  for (int n = 0; n < kStates; ++n) {
    const Vector7 q = random.q(robot_model.joint_limits), dq = random.uniform(2.0);
    const TotalLoad load = random_load(random);
    const Matrix4 F_T_EE = random_frame(random);
    const Vector3 g_earth = random.uniform(10.0).head<3>();
    const Model model = reference_model(robot_model, load, F_T_EE, g_earth);
    Data data;
    forward_kinematics(model, data, q);
    for (int frame = 1; frame <= 9; ++frame) {
      SCOPED_TRACE("frame " + std::to_string(frame));
      const Frame csp_frame = static_cast<Frame>(frame - 1);   // libfranka's order: joints 1-7, flange, EE
      EXPECT_TRUE(near(library.pose(frame, q, F_T_EE), frame_pose(data, csp_frame).matrix(), 1e-12));
      Matrix6x7 J;
      zero_jacobian(data, csp_frame, J);
      EXPECT_TRUE(near(library.zero_jacobian(frame, q, F_T_EE), J, 1e-12));
      body_jacobian(data, csp_frame, J);
      EXPECT_TRUE(near(library.body_jacobian(frame, q, F_T_EE), J, 1e-12));
    }
    const Model no_gravity = with_gravity(model, Vector3::Zero());
    Vector7 bias, tau, c, g;
    rnea(no_gravity, data, q, Vector7::Zero(), Vector7::Zero(), bias);
    Matrix7 M;
    for (int j = 0; j < kNumJoints; ++j) {
      rnea(no_gravity, data, q, Vector7::Zero(), Vector7::Unit(j), tau);
      M.col(j) = tau - bias;
    }
    rnea(no_gravity, data, q, dq, Vector7::Zero(), c);
    rnea(model, data, q, Vector7::Zero(), Vector7::Zero(), g);
    EXPECT_TRUE(near(library.mass(q, load), M, 1e-10));
    EXPECT_TRUE(near(library.coriolis(q, dq, load), c, 1e-10));
    EXPECT_TRUE(near(library.gravity(q, load, g_earth), g, 1e-10));
  }
}

// (b) The Jacobians are the derivatives of the library's own poses: zero Jacobians directly, body
// Jacobians rotated into the frame; joint 1's are constant (no q argument).
TEST_P(FciModel, JacobiansAreTheDerivativesOfTheLibrarysPoses) {
  for (int n = 0; n < kStates; ++n) {
    const Vector7 q = random.q(robot_model.joint_limits);
    const Matrix4 F_T_EE = random_frame(random);
    for (int frame = 1; frame <= 9; ++frame) {
      SCOPED_TRACE("frame " + std::to_string(frame));
      const Matrix6x7 numeric = finite_difference_jacobian(library, frame, q, F_T_EE);
      EXPECT_TRUE(near(library.zero_jacobian(frame, q, F_T_EE), numeric, 1e-8));
      const Matrix3 R = library.pose(frame, q, F_T_EE).topLeftCorner<3, 3>();
      Matrix6x7 in_frame;
      in_frame << R.transpose() * numeric.topRows<3>(), R.transpose() * numeric.bottomRows<3>();
      EXPECT_TRUE(near(library.body_jacobian(frame, q, F_T_EE), in_frame, 1e-8));
    }
  }
}

// (c) Physical laws: M symmetric positive definite; c quadratic in dq, zero at rest, and the
// Christoffel form of the library's own M; g the gradient of the potential energy of the links'
// CoMs and the load placed by the library's poses.
TEST_P(FciModel, MassCoriolisAndGravityObeyTheLawsOfMechanics) {
  constexpr double h = 1e-6;
  for (int n = 0; n < kStates; ++n) {
    const Vector7 q = random.q(robot_model.joint_limits), dq = random.uniform(2.0);
    const TotalLoad load = random_load(random);
    const Vector3 g_earth = random.uniform(10.0).head<3>();

    const Matrix7 M = library.mass(q, load);
    EXPECT_TRUE(near(M, M.transpose(), 1e-12));
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix7>(M).eigenvalues().minCoeff(), 0.0);

    const Vector7 c = library.coriolis(q, dq, load);
    EXPECT_TRUE(near(library.coriolis(q, Vector7::Zero(), load), Vector7::Zero(), 1e-12));
    EXPECT_TRUE(near(library.coriolis(q, 2.0 * dq, load), 4.0 * c, 1e-9));
    // c_i = sum_k dM_ij/dq_k dq_k dq_j - 1/2 dq^T dM/dq_i dq.
    Vector7 christoffel = Vector7::Zero();
    Matrix7 M_dot = Matrix7::Zero();
    for (int k = 0; k < kNumJoints; ++k) {
      const Vector7 step = h * Vector7::Unit(k);
      const Matrix7 dM_dqk = (library.mass(q + step, load) - library.mass(q - step, load)) / (2 * h);
      M_dot += dM_dqk * dq[k];
      christoffel[k] -= 0.5 * dq.dot(dM_dqk * dq);
    }
    christoffel += M_dot * dq;
    EXPECT_TRUE(near(c, christoffel, 1e-6));

    Vector7 dV_dq;
    for (int k = 0; k < kNumJoints; ++k) {
      const Vector7 step = h * Vector7::Unit(k);
      dV_dq[k] = (potential_energy_of(library, robot_model, q + step, load, g_earth) -
                  potential_energy_of(library, robot_model, q - step, load, g_earth)) / (2 * h);
    }
    EXPECT_TRUE(near(library.gravity(q, load, g_earth), dV_dq, 1e-6));
  }
}

// A load no rigid body has (negative mass, non-symmetric inertia): NaN, as CSP's franka::Model.
TEST_P(FciModel, ALoadNoBodyHasGivesNaN) {
  const Vector7 q = random.q(robot_model.joint_limits);
  TotalLoad negative = random_load(random);
  negative.mass = -1.0;
  TotalLoad skewed = random_load(random);
  skewed.inertia(0, 1) += 0.01;
  EXPECT_TRUE(library.mass(q, negative).array().isNaN().all());
  EXPECT_TRUE(library.coriolis(q, Vector7::Ones(), skewed).array().isNaN().all());
  EXPECT_TRUE(library.gravity(q, negative, Vector3(0.0, 0.0, -9.81)).array().isNaN().all());
}

INSTANTIATE_TEST_SUITE_P(Robots, FciModel, ::testing::Values("panda", "fr3"));

// (d) The block really is read: libraries of two robots, and of two inertia sets of one robot,
// loaded side by side, give different masses (and the same poses for the same kinematics).
TEST(FciModelLibrary, EachLibraryComputesWithTheRobotModelWrittenIntoIt) {
  const FciModelLibrary panda(library_file(robot_parameters("panda", "libfranka_fit"), "fci_model_d_panda"));
  const FciModelLibrary gaz(library_file(robot_parameters("panda", "gaz2019"), "fci_model_d_gaz"));
  const FciModelLibrary fr3(library_file(robot_parameters("fr3"), "fci_model_d_fr3"));
  const Vector7 q = (Vector7() << 0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7).finished();
  const TotalLoad none;
  EXPECT_GT((panda.mass(q, none) - fr3.mass(q, none)).cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_GT((panda.mass(q, none) - gaz.mass(q, none)).cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_TRUE(near(panda.pose(8, q), gaz.pose(8, q), 0.0));
}

// libfranka's own model (libfcimodels served by a Panda, and libfranka's FR3 model tests) for the
// robot models the server sends.
TEST(FciModelLibrary, ReproducesLibfrankasModelOfThePandaAndTheFr3) {
  const json& oracles = franka_models().at("oracles");
  auto matrix = [](const json& values, bool column_major) {
    const Eigen::Matrix<double, 49, 1> flat = vector_from<49>(values);
    const Matrix7 m = Eigen::Map<const Matrix7>(flat.data());
    return column_major ? m : Matrix7(m.transpose());
  };
  const Vector3 g_earth(0.0, 0.0, -9.81);
  {
    const FciModelLibrary panda(library_file(robot_parameters("panda", "libfranka_fit"), "fci_model_o_panda"));
    const json& dump = oracles.at("panda_libfranka_model_dump");
    for (const char* name : {"zero_no_load", "ready_no_load"}) {
      SCOPED_TRACE(name);
      const json& c = dump.at(name);
      const Vector7 q = v7(c.at("q"));
      EXPECT_TRUE(near(panda.gravity(q, {}, g_earth), v7(c.at("gravity")), 1e-9));
      EXPECT_TRUE(near(panda.mass(q, {}), matrix(c.at("mass_colmajor"), true), 1e-9));
    }
    const json& ready = dump.at("ready_no_load");
    EXPECT_TRUE(near(panda.coriolis(v7(ready.at("q")), Vector7::Ones(), {}), v7(ready.at("coriolis_at_dq_all_ones")), 1e-9));
    EXPECT_TRUE(near(panda.pose(8, v7(ready.at("q"))).topRightCorner<3, 1>(), v3(ready.at("pose_flange_p")), 1e-9));
    // With the hand and a load: g and the end effector's position (the dump's Coriolis is not a
    // rigid lumped load: test_oracles.cpp OracleLibfrankaDump.ReadyPoseHandAndLoad).
    const json& loaded = dump.at("ready_hand_and_load");
    const Vector7 q = v7(loaded.at("q"));
    const TotalLoad hand_and_load{loaded.at("m_total").get<double>(), v3(loaded.at("F_x_Ctotal")),
                                  v3(loaded.at("I_total_diag")).asDiagonal()};
    const Matrix4 F_T_EE = from_data<Matrix4>(vector_from<16>(loaded.at("F_T_EE_column_major")).data());
    EXPECT_TRUE(near(panda.gravity(q, hand_and_load, g_earth), v7(loaded.at("gravity")), 1e-6));
    EXPECT_TRUE(near(panda.pose(9, q, F_T_EE).topRightCorner<3, 1>(), v3(loaded.at("pose_EE_p")), 1e-6));
  }
  {
    const FciModelLibrary fr3(library_file(robot_parameters("fr3"), "fci_model_o_fr3"));
    const json& tests = oracles.at("fr3_libfranka_model_tests");
    const json& none = tests.at("q_zero_no_load");
    EXPECT_TRUE(near(fr3.gravity(Vector7::Zero(), {}, g_earth), v7(none.at("gravity")), 1e-5));
    EXPECT_TRUE(near(fr3.mass(Vector7::Zero(), {}), matrix(none.at("mass_rowmajor"), false), 1e-5));
    const json& hand = tests.at("q_zero_hand_like_load");
    const TotalLoad hand_like{hand.at("m_total").get<double>(), v3(hand.at("F_x_Ctotal")),
                              v3(hand.at("I_total_diag")).asDiagonal()};
    EXPECT_TRUE(near(fr3.gravity(Vector7::Zero(), hand_like, g_earth), v7(hand.at("gravity")), 1e-5));
    EXPECT_TRUE(near(fr3.mass(Vector7::Zero(), hand_like), matrix(hand.at("mass_rowmajor"), false), 1e-5));
    EXPECT_TRUE(near(fr3.coriolis(Vector7::Zero(), Vector7::Ones(), hand_like), v7(hand.at("coriolis_at_dq_all_ones")), 1e-5));
  }
}

// The file as built (never written by a server) refuses to compute: a message and abort.
TEST(FciModelLibraryDeathTest, TheLibraryAsBuiltAbortsSayingItsModelWasNeverWritten) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string as_built = fci::model_library_path();
  ASSERT_TRUE(std::filesystem::is_regular_file(as_built)) << as_built;
  const FciModelLibrary library(as_built);
  EXPECT_DEATH(library.pose(2, Vector7::Zero()), "robot model was never written");
  EXPECT_DEATH(library.mass(Vector7::Zero(), {}), "robot model was never written");
}

// The server's errors name the file and what is wrong with it.
std::string model_library_error(const std::string& path) {
  try {
    fci::model_library_for(robot_parameters("fr3"), path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(FciModelLibrary, AFileWithoutExactlyOneParameterBlockIsRefusedByName) {
  const std::string as_built = read_text(fci::model_library_path());
  const std::string marker(fci::kParameterBlockMarker, sizeof fci::kParameterBlockMarker);
  const std::string no_marker = write_temp("fci_no_marker.so", "an ELF file it is not");
  EXPECT_EQ(model_library_error(no_marker),
            "FCI model library " + no_marker + ": no parameter block (its marker is not in the file: not libcsp_fci_model.so?)");
  const std::string two = write_temp("fci_two_markers.so", as_built + marker);
  EXPECT_EQ(model_library_error(two), "FCI model library " + two + ": more than one parameter block marker");
  const std::string cut = write_temp("fci_cut.so", "header" + marker + "short");
  EXPECT_EQ(model_library_error(cut), "FCI model library " + cut + ": the parameter block is cut off by the end of the file");
  const std::string missing = (temp_dir() / "no_such_library.so").string();
  EXPECT_EQ(model_library_error(missing), "FCI model library " + missing + ": cannot open it");

  ModelParameters not_finite = robot_parameters("fr3");
  not_finite.links[3].mass = std::nan("");
  EXPECT_THROW(fci::model_library_for(not_finite), std::runtime_error);
}

// The written copy differs from the file as built in the block's count and values only.
TEST(FciModelLibrary, TheServerWritesOnlyTheParameterBlock) {
  const std::string as_built = read_text(fci::model_library_path());
  const std::vector<std::uint8_t> written = fci::model_library_for(robot_parameters("panda", "libfranka_fit"));
  ASSERT_EQ(written.size(), as_built.size());
  const std::size_t block = as_built.find(std::string(fci::kParameterBlockMarker, sizeof fci::kParameterBlockMarker));
  ASSERT_NE(block, std::string::npos);
  const std::size_t values_begin = block + offsetof(fci::ParameterBlock, value_count);
  const std::size_t values_end = block + sizeof(fci::ParameterBlock);
  for (std::size_t k = 0; k < written.size(); ++k) {
    const bool outside_the_values = k < values_begin || k >= values_end;
    if (outside_the_values) {
      ASSERT_EQ(written[k], static_cast<std::uint8_t>(as_built[k])) << "byte " << k;
    }
  }
  std::uint64_t value_count = 0;
  std::memcpy(&value_count, written.data() + values_begin, sizeof value_count);
  EXPECT_EQ(value_count, fci::kParameterCount);
}

// Self-contained: it needs only glibc (libc, libm, libmvec for csp_dynamics' vectorised sin/cos)
// and the C++ runtime, and exports exactly libfranka's 31 functions and the parameter block.
std::vector<std::string> lines_matching(const std::string& text, const std::string& prefix) {
  std::vector<std::string> found;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.find(prefix) != std::string::npos) found.push_back(line);
  return found;
}

TEST(FciModelLibrary, NeedsOnlyTheCAndCxxRuntimesAndExportsExactlyLibfrankasFunctions) {
  const std::string path = fci::model_library_path();
  const ProgramRun dynamic = run_program(CSP_READELF, {"-d", "-W", path});
  ASSERT_EQ(dynamic.exit_code, 0) << dynamic.err;
  const std::vector<std::string> needed = lines_matching(dynamic.out, "(NEEDED)");
  EXPECT_FALSE(needed.empty());
  // GCC's sanitizers add their shared runtimes (clang's resolve against the sanitized program's).
  const std::string runtimes = kSanitized ? "|libasan|libubsan" : "";
  const std::regex allowed(R"(.*Shared library: \[(libc|libm|libmvec|libstdc\+\+|libgcc_s|ld-linux-x86-64)" + runtimes +
                           R"()\.so\.[0-9]+\].*)");
  for (const std::string& line : needed) EXPECT_TRUE(std::regex_match(line, allowed)) << line;

  const ProgramRun symbols = run_program(CSP_NM, {"-D", "--defined-only", "--format=just-symbols", path});
  ASSERT_EQ(symbols.exit_code, 0) << symbols.err;
  std::set<std::string> exported;
  std::istringstream names(symbols.out);
  for (std::string name; names >> name;) exported.insert(name);
  std::set<std::string> expected{"M_NE", "c_NE", "g_NE", "csp_fci_model_parameters"};
  for (int frame = 1; frame <= 9; ++frame)
    for (const char* kind : {"O_T_J", "O_J_J", "Ji_J_J"}) expected.insert(kind + std::to_string(frame));
  EXPECT_EQ(exported, expected);
}

}  // namespace
}  // namespace csp::test
