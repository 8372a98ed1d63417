// Test helpers: the shared data file, robot files, seeded random states.
#pragma once

#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <cstdio>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/robot_config.hpp"

namespace csp::test {

// Under the sanitizers (about 10x slower) the costliest sweeps run fewer cases: every code path still
// runs there, and the Release build runs every case.
#if defined(CSP_SANITIZE_BUILD)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
constexpr int fewer_when_sanitized(int all, int sanitized) { return kSanitized ? sanitized : all; }

inline std::string robot_file(const std::string& name) {
  return std::string(CSP_SOURCE_DIR) + "/configs/robots/" + name + ".yaml";
}

// ../shared/data/franka_models.json, parsed once.
inline const nlohmann::json& franka_models() {
  static const nlohmann::json data = [] {
    std::ifstream in(std::string(CSP_SHARED_DATA_DIR) + "/franka_models.json");
    if (!in) throw std::runtime_error("cannot open franka_models.json under " CSP_SHARED_DATA_DIR);
    return nlohmann::json::parse(in);
  }();
  return data;
}

template <int N>
Eigen::Matrix<double, N, 1> vector_from(const nlohmann::json& values) {
  if (values.size() != N) throw std::runtime_error("unexpected length in franka_models.json");
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v[i] = values.at(i).get<double>();
  return v;
}

inline Model make_model(const std::string& robot, ModelOptions options = {}) {
  return Model(model_parameters(load_robot_config(robot_file(robot)), options));
}

// The model `csp gap` diagnoses with in the gap tests: the Panda without friction (friction is the
// library's to find).
inline Model diagnosing_model() {
  ModelOptions options;
  options.friction = "none";
  return make_model("panda", options);
}

// The scenario a plain `csp emulate` runs.
inline const std::string kDefaultScenario = std::string(CSP_SOURCE_DIR) + "/configs/scenarios/default.yaml";

// A file's bytes; throws when it cannot be read (a missing output is a failure, not "").
inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// One sampled state of the arm's motion.
struct State {
  Vector7 q, dq, ddq;
};

// The mass matrix M(q) by CRBA.
inline Matrix7 mass_of(const Model& model, const Vector7& q) {
  Data data;
  crba(model, data, q);
  return data.mass_matrix;
}

inline Vector7 v7(const nlohmann::json& values) { return vector_from<7>(values); }
inline Vector3 v3(const nlohmann::json& values) { return vector_from<3>(values); }

inline Matrix3 matrix3_rowmajor(const nlohmann::json& rows) {
  Matrix3 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = rows.at(r).at(c).get<double>();
  return m;
}

// g(q) of a model, with a workspace of its own.
inline Vector7 gravity_of(const Model& model, const Vector7& q) {
  Data data;
  Vector7 g;
  gravity_torque(model, data, q, g);
  return g;
}

// Potential energy from the parameters (not from the Model's lumped bodies): every link CoM, the
// end effector and the load, V = -sum m_i g . c_i.
inline double potential_energy(const Model& model, const Vector7& q) {
  Data data;
  forward_kinematics(model, data, q);
  const ModelParameters& p = model.parameters();
  double V = 0.0;
  for (int i = 0; i < kNumJoints; ++i) V -= p.links[i].mass * p.gravity.dot(data.O_T_joint[i] * p.links[i].com);
  V -= p.end_effector.mass * p.gravity.dot(data.O_T_F * p.end_effector.com);
  V -= p.load.mass * p.gravity.dot(data.O_T_F * p.load.com);
  return V;
}

// Uniformly random joint positions within the limits; velocities and accelerations of a few rad/s.
struct RandomStates {
  explicit RandomStates(unsigned seed) : engine(seed) {}
  Vector7 q(const JointLimits& limits) {
    Vector7 v;
    for (int i = 0; i < kNumJoints; ++i) v[i] = std::uniform_real_distribution<double>(limits.q_min[i], limits.q_max[i])(engine);
    return v;
  }
  Vector7 uniform(double bound) {
    Vector7 v;
    for (int i = 0; i < kNumJoints; ++i) v[i] = std::uniform_real_distribution<double>(-bound, bound)(engine);
    return v;
  }
  std::mt19937_64 engine;
};

// Max |actual - expected| <= tolerance, with the worst entry in the failure message.
template <typename A, typename B>
inline ::testing::AssertionResult near(const Eigen::MatrixBase<A>& actual, const Eigen::MatrixBase<B>& expected,
                                double tolerance) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    return ::testing::AssertionFailure() << "size mismatch";
  Eigen::Index r = 0, c = 0;
  const double worst = (actual - expected).cwiseAbs().maxCoeff(&r, &c);
  if (worst <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max |difference| " << worst << " > " << tolerance << " at (" << r << ", "
                                       << c << "): actual " << actual(r, c) << ", expected " << expected(r, c)
                                       << "\nactual:\n" << actual << "\nexpected:\n" << expected;
}

// A directory for this process's generated files, removed when the test program ends.
inline const std::filesystem::path& temp_dir() {
  struct Directory {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("csp_test_" + std::to_string(::getpid()));
    Directory() { std::filesystem::create_directories(path); }
    ~Directory() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Directory directory;
  return directory.path;
}

// Writes `text` (bytes as they are) to a file of temp_dir() and returns its path.
inline std::string write_temp(const std::string& file_name, const std::string& text) {
  const std::string path = (temp_dir() / file_name).string();
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
  return path;
}

// A program run to its end: exit code, standard output, standard error.
struct ProgramRun {
  int exit_code = -1;
  std::string out, err;
};

// Runs `executable args...` (each argument shell-quoted): stdout through a pipe, stderr through a
// file in temp_dir().
inline ProgramRun run_program(const std::string& executable, const std::vector<std::string>& args) {
  static int count = 0;
  const std::string err_path = (temp_dir() / ("stderr_run_" + std::to_string(count++) + ".txt")).string();
  auto quote = [](const std::string& arg) {
    std::string quoted = "'";
    for (const char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
  };
  std::string command = quote(executable);
  // append(), not "literal" + string: GCC 12 warns falsely (-Wrestrict, bug 105329) on that once inlined.
  for (const auto& arg : args) command.append(" ").append(quote(arg));
  command.append(" 2>").append(quote(err_path));
  ProgramRun run;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed: " + command);
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) run.out.append(buffer, n);
  const int status = ::pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream err(err_path);
  run.err.assign(std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>());
  std::filesystem::remove(err_path);
  return run;
}

// The message of reading a joint log that must fail, or "no error".
inline std::string joint_log_error(const std::string& path) {
  try {
    read_joint_log_csv(path);
  } catch (const JointLogError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace csp::test
