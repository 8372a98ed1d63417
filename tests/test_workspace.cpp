// csp workspace: the sampler (determinism, reachability, histogram totals, convergence of the
// maximum reach to its analytic value) and the command line (figures, exit codes).
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "csp/dynamics/workspace.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

Model panda(const std::string& end_effector = "none") {
  ModelOptions options;
  options.end_effector = end_effector;
  return make_model("panda", options);
}

// Analytic maximum distance from the shoulder (joint-2 origin O2) to the flange, or to the hand's
// TCP 0.1034 m further along the flange z axis, from Franka's MDH lengths alone (no FK):
//   O2 -> O4 = d3 z3 + a4 x3       (z3 perpendicular to x3), length sqrt(d3^2 + a4^2) for every q
//   O4 -> O5 = a5 x4 + d5 z5       (x4 perpendicular to z5), length sqrt(a5^2 + d5^2)
//   O5 -> F  = a7 x6 + d_F z7      (x6 perpendicular to z7), length sqrt(a7^2 + d_F^2)
// (d4 = a6 = d6 = d7 = 0). The triangle inequality bounds the reach by the sum of the three
// lengths, and the bound is attained within the joint limits: q4 makes the first two segments
// collinear, q5 = 0 keeps the wrist segment in their plane and q6 lines it up with them. So the
// sum is the maximum itself, 0.857893 m for the flange (Franka publishes 855 mm).
constexpr double d3 = 0.316, a4 = 0.0825, a5 = -0.0825, d5 = 0.384, a7 = 0.088, d_flange = 0.107, d_hand = 0.1034;

double analytic_max_reach(double wrist_length) {
  return std::hypot(d3, a4) + std::hypot(a5, d5) + std::hypot(a7, wrist_length);
}

// The configuration that attains analytic_max_reach (q1, q2, q3, q7 do not change the distance).
Vector7 straight_arm(double wrist_length) {
  Vector7 q = Vector7::Zero();
  q[3] = -(std::atan(a4 / d3) + std::atan(-a5 / d5));
  q[5] = M_PI / 2 + std::atan(-a5 / d5) + std::atan2(wrist_length, a7);
  return q;
}

double distance_from_shoulder(const Model& model, const Vector7& q, Frame frame) {
  Data data;
  forward_kinematics(model, data, q);
  return (frame_pose(data, frame).translation - data.O_T_joint[1].translation).norm();
}

WorkspaceOptions options_for(std::int64_t samples, std::uint64_t seed, Frame frame = Frame::kEndEffector) {
  WorkspaceOptions options;
  options.samples = samples;
  options.seed = seed;
  options.frame = frame;
  options.grid = 100;
  return options;
}

void expect_same(const ReachStatistics& a, const ReachStatistics& b) {
  EXPECT_EQ(a.max_reach, b.max_reach);
  EXPECT_EQ(a.q_at_max_reach, b.q_at_max_reach);
  EXPECT_EQ(a.max_radius, b.max_radius);
  EXPECT_EQ(a.z_min, b.z_min);
  EXPECT_EQ(a.z_max, b.z_max);
}

TEST(WorkspaceSampling, SameSeedSameResult) {
  const Model model = panda("hand");
  const WorkspaceResult a = sample_workspace(model, options_for(20000, 7));
  const WorkspaceResult b = sample_workspace(model, options_for(20000, 7));
  expect_same(a.flange, b.flange);
  expect_same(a.end_effector, b.end_effector);
  EXPECT_EQ(a.side.counts, b.side.counts);
  EXPECT_EQ(a.top.counts, b.top.counts);

  const WorkspaceResult other = sample_workspace(model, options_for(20000, 8));
  EXPECT_NE(a.flange.max_reach, other.flange.max_reach);
}

TEST(WorkspaceSampling, EverySampleIsWithinLimitsAndMatchesForwardKinematics) {
  const Model model = panda("hand");
  const JointLimits& limits = model.parameters().joint_limits;
  Data data;
  std::int64_t seen = 0;
  double worst = 0.0;
  const WorkspaceResult result = sample_workspace(model, options_for(20000, 3), [&](const WorkspacePoint& p) {
    ++seen;
    EXPECT_TRUE((p.q.array() >= limits.q_min.array()).all() && (p.q.array() <= limits.q_max.array()).all());
    forward_kinematics(model, data, p.q);
    worst = std::max({worst, (data.O_T_F.translation - p.flange).norm(), (data.O_T_EE.translation - p.end_effector).norm(),
                      (p.shoulder - Vector3(0, 0, 0.333)).norm()});
  });
  EXPECT_EQ(seen, 20000);
  EXPECT_LT(worst, 1e-12);
  // The hand's TCP is 0.1034 m beyond the flange along the flange z axis.
  EXPECT_GT(result.end_effector.max_reach, result.flange.max_reach + 0.05);
}

TEST(WorkspaceSampling, UniformSamplesCoverTheJointRanges) {
  const Model model = panda();
  const JointLimits& limits = model.parameters().joint_limits;
  std::mt19937_64 engine(11);
  Vector7 lowest = limits.q_max, highest = limits.q_min, sum = Vector7::Zero();
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const Vector7 q = uniform_joint_sample(limits, engine);
    lowest = lowest.cwiseMin(q), highest = highest.cwiseMax(q), sum += q;
  }
  const Vector7 range = limits.q_max - limits.q_min;
  EXPECT_TRUE(((lowest - limits.q_min).array() < 1e-3 * range.array()).all());
  EXPECT_TRUE(((limits.q_max - highest).array() < 1e-3 * range.array()).all());
  // Mean within 5 standard errors (range / sqrt(12 n)) of the midpoint.
  const Vector7 error = sum / n - (limits.q_min + limits.q_max) / 2;
  EXPECT_TRUE((error.array().abs() < 5 * range.array() / std::sqrt(12.0 * n)).all()) << error.transpose();
}

TEST(WorkspaceSampling, HistogramCountsSumToSamples) {
  for (const Frame frame : {Frame::kFlange, Frame::kEndEffector}) {
    const WorkspaceResult r = sample_workspace(panda("hand"), options_for(30001, 5, frame));
    EXPECT_EQ(r.side.inside(), 30001u);
    EXPECT_EQ(r.top.inside(), 30001u);
    EXPECT_EQ(r.side.outside + r.top.outside, 0u);
    EXPECT_EQ(r.side.nx, 100);
    EXPECT_DOUBLE_EQ(r.side.cell_width(), r.side.cell_height());
  }
}

TEST(WorkspaceSampling, RejectsBadOptions) {
  const Model model = panda();
  EXPECT_THROW(sample_workspace(model, options_for(0, 1)), std::invalid_argument);
  EXPECT_THROW(sample_workspace(model, options_for(-3, 1)), std::invalid_argument);
  EXPECT_THROW(sample_workspace(model, options_for(10, 1, Frame::kJoint4)), std::invalid_argument);
  WorkspaceOptions no_grid = options_for(10, 1);
  no_grid.grid = 0;
  EXPECT_THROW(sample_workspace(model, no_grid), std::invalid_argument);
}

TEST(WorkspaceReach, AnalyticMaximumIsAttainedWithinTheLimits) {
  const Model flange_model = panda(), hand_model = panda("hand");
  const JointLimits& limits = flange_model.parameters().joint_limits;
  for (const double wrist : {d_flange, d_flange + d_hand}) {
    const Vector7 q = straight_arm(wrist);
    EXPECT_TRUE((q.array() >= limits.q_min.array()).all() && (q.array() <= limits.q_max.array()).all()) << q.transpose();
    const double reach = wrist == d_flange ? distance_from_shoulder(flange_model, q, Frame::kFlange)
                                           : distance_from_shoulder(hand_model, q, Frame::kEndEffector);
    EXPECT_NEAR(reach, analytic_max_reach(wrist), 1e-12);
  }
  EXPECT_NEAR(analytic_max_reach(d_flange), 0.857893, 1e-6);
  EXPECT_NEAR(analytic_max_reach(d_flange + d_hand), 0.947416, 1e-6);
  // The grid-sizing bound is looser but must hold.
  EXPECT_GE(reach_upper_bound(flange_model, Frame::kFlange), analytic_max_reach(d_flange));
  EXPECT_GE(reach_upper_bound(hand_model, Frame::kEndEffector), analytic_max_reach(d_flange + d_hand));
}

TEST(WorkspaceReach, SampledMaximumConvergesToAnalyticMaximum) {
  // Near the maximum the reach falls quadratically in q4, q5, q6, so the chance that a sample lands
  // within delta of it grows like delta^(3/2). With seed 1, 2e5 samples come within 0.05 mm (flange)
  // and 0.014 mm (hand); a 1 mm tolerance is ~90 times likelier per sample, so no seed should miss it.
  // The sampled value can never exceed the analytic maximum.
  constexpr double kTolerance = 1e-3;
  const WorkspaceResult r = sample_workspace(panda("hand"), options_for(200000, 1));
  const double flange_max = analytic_max_reach(d_flange), hand_max = analytic_max_reach(d_flange + d_hand);
  EXPECT_LE(r.flange.max_reach, flange_max + 1e-12);
  EXPECT_GT(r.flange.max_reach, flange_max - kTolerance);
  EXPECT_LE(r.end_effector.max_reach, hand_max + 1e-12);
  EXPECT_GT(r.end_effector.max_reach, hand_max - kTolerance);
  // The arm is symmetric about the joint-1 axis, so the horizontal radius can approach the same value.
  EXPECT_LE(r.flange.max_radius, flange_max + 1e-12);
  EXPECT_GT(r.flange.max_radius, flange_max - 3 * kTolerance);
}

// --- command line ---

struct CliRun {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::filesystem::path scratch_dir() {
  return std::filesystem::temp_directory_path() / ("csp_workspace_test_" + std::to_string(::getpid()));
}

std::filesystem::path scratch(const std::string& name) {
  std::filesystem::create_directories(scratch_dir());
  return scratch_dir() / name;
}

CliRun run_csp(const std::string& arguments) {
  const auto out = scratch("stdout.txt"), err = scratch("stderr.txt");
  const std::string command = std::string("'") + CSP_EXECUTABLE + "' " + arguments + " >'" + out.string() + "' 2>'" +
                              err.string() + "'";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

TEST(WorkspaceCli, WritesSideAndTopFigures) {
  const auto dir = scratch("figures");
  std::filesystem::remove_all(dir);
  const auto points = scratch("points.csv");
  const CliRun run = run_csp("workspace --ee hand --samples 5000 --seed 3 --grid 80 --out '" + dir.string() +
                          "' --points '" + points.string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* name : {"workspace_side.svg", "workspace_top.svg"}) {
    const std::string svg = slurp(dir / name);
    EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << name;
    EXPECT_NE(svg.find("<svg"), std::string::npos) << name;
    EXPECT_NE(svg.find("</svg>"), std::string::npos) << name;
    EXPECT_NE(svg.find("855 mm"), std::string::npos) << name;
  }
  EXPECT_NE(run.out.find("max reach from the shoulder"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("855 mm"), std::string::npos) << run.out;
  // Header plus one row of six numbers per sample.
  std::ifstream csv(points);
  std::string line;
  int rows = 0;
  std::getline(csv, line);
  EXPECT_EQ(line, "flange_x,flange_y,flange_z,ee_x,ee_y,ee_z");
  while (std::getline(csv, line)) {
    ++rows;
    if (rows == 1) {
      EXPECT_EQ(std::count(line.begin(), line.end(), ','), 5) << line;
    }
  }
  EXPECT_EQ(rows, 5000);
  std::filesystem::remove_all(scratch_dir());
}

// Progress (apps/progress.hpp): stderr is a file here, not a terminal, so the command is quiet but
// for one summary line, unless --progress asks; then lines with the stage, a growing percentage,
// the rate and the time left. stdout, the result, is the same either way.
TEST(WorkspaceCli, ProgressOnStderrWhenAskedAndOneSummaryLineAlways) {
  const auto dir = scratch("progress");
  const std::string arguments = "workspace --samples 300000 --grid 40 --out '" + dir.string() + "'";
  const CliRun quiet = run_csp(arguments);
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(std::count(quiet.err.begin(), quiet.err.end(), '\n'), 1) << quiet.err;
  EXPECT_EQ(quiet.err.rfind("csp workspace: 300000 samples, figures in " + dir.string() + " (", 0), 0u) << quiet.err;

  const CliRun shown = run_csp(arguments + " --progress");
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  std::vector<std::string> lines;
  std::istringstream err(shown.err);
  for (std::string line; std::getline(err, line);) lines.push_back(line);
  ASSERT_GE(lines.size(), 4u) << shown.err;   // 0 %, at least two steps of a tenth, the summary
  EXPECT_EQ(lines.back().rfind("csp workspace: 300000 samples", 0), 0u) << shown.err;
  double last_percent = -1.0;
  for (std::size_t k = 0; k + 1 < lines.size(); ++k) {
    ASSERT_EQ(lines[k].rfind("csp workspace: sampling ", 0), 0u) << lines[k];
    const double percent = std::stod(lines[k].substr(std::string("csp workspace: sampling ").size()));
    EXPECT_GT(percent, last_percent) << shown.err;
    last_percent = percent;
    if (k > 0) {   // a rate and the time left once something is done
      EXPECT_NE(lines[k].find("/s, "), std::string::npos) << lines[k];   // e.g. "2.3 M/s, <1 s left"
      EXPECT_NE(lines[k].find(" left)"), std::string::npos) << lines[k];
    }
  }
  // The same result on stdout, but for the line that times the run.
  auto without_time = [](const std::string& out) { return out.substr(0, out.find("\ntime: ")); };
  EXPECT_EQ(without_time(shown.out), without_time(quiet.out));
  std::filesystem::remove_all(scratch_dir());
}

TEST(WorkspaceCli, BadArgumentsExitWithTwoAndOneLine) {
  const auto not_a_dir = scratch("plain_file");
  std::ofstream(not_a_dir) << "x";
  const auto dir = scratch("unused");
  for (const std::string& arguments : std::vector<std::string>{
           "--samples 0", "--samples=-5", "--samples many", "--seed -1", "--grid 3", "--ee claw",
        "--samples 10 --out '" + (not_a_dir / "sub").string() + "'"}) {
    const std::string extra = arguments.find("--out") == std::string::npos ? " --out '" + dir.string() + "'" : "";
    const CliRun run = run_csp("workspace " + arguments + extra);
    EXPECT_EQ(run.exit_code, 2) << arguments;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << arguments << ": " << run.err;
    EXPECT_EQ(run.err.rfind("csp", 0), 0u) << run.err;
  }
  std::filesystem::remove_all(scratch_dir());
}

}  // namespace
}  // namespace csp::test
