// Transfers between rest poses (docs/planning-transfers.md): OMPL through csp_ompl_bridge, timed by
// rest-to-rest septic segments. References independent of the planner: the septic's peaks by dense
// sampling, derivatives by finite differences, every returned plan re-sampled (the timed trajectory
// at 1 kHz, or joint steps of 1e-3 rad) against every pair exactly (check_all_pairs, not the
// certified motion check the planner used), limits against the robot file's numbers, the tool speed
// from finite differences of forward kinematics, and the same seed run in a second process.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/ompl_bridge.hpp"
#include "csp/planners/profile.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/trajectory_check.hpp"
#include "csp/planners/transfer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using planners::ClearanceChecker;
using planners::TransferOptions;
using planners::TransferPlan;
namespace ompl_bridge = planners::ompl_bridge;

#if defined(CSP_SANITIZE_BUILD)
// The sanitizer build runs 10-20x slower: it keeps the OMPL set-up and solve paths (ompl/ompl#601)
// with fewer scenes.
constexpr int kRandomScenes = 4;
const std::vector<std::string> kScenes = {"ultrasound_abdomen", "craniotomy"};
const std::vector<std::string> kRobots = {"fr3"};
#else
constexpr int kRandomScenes = 50;
const std::vector<std::string> kScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};
const std::vector<std::string> kRobots = {"panda", "fr3"};
#endif

std::string scene_file(const std::string& name) { return std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + name + ".yaml"; }

Model scene_model(const std::string& robot, const Scene& scene) {
  return Model(with_tool(model_parameters(load_robot_config(robot_file(robot)), {}), scene.tool));
}

// ---------------- Septic segments ----------------

TEST(Septic, PeaksMatchDenseSampling) {
  double ds = 0.0, dds = 0.0, ddds = 0.0;
  const int n = 1'000'000;
  for (int k = 0; k <= n; ++k) {
    const auto s = planners::septic(static_cast<double>(k) / n);
    ds = std::max(ds, std::abs(s.ds));
    dds = std::max(dds, std::abs(s.dds));
    ddds = std::max(ddds, std::abs(s.ddds));
  }
  // The sampled maxima approach the closed forms from below (to the grid's O(1/n^2)).
  EXPECT_NEAR(ds, 2.1875, 1e-9);
  EXPECT_NEAR(dds, 7.5132, 1e-4);
  EXPECT_NEAR(ddds, 52.5, 1e-9);
  EXPECT_LE(ds, planners::kSepticPeakVelocity + 1e-12);
  EXPECT_LE(dds, planners::kSepticPeakAcceleration + 1e-12);
  EXPECT_LE(ddds, planners::kSepticPeakJerk + 1e-12);
  EXPECT_NEAR(dds, planners::kSepticPeakAcceleration, 1e-9);
}

TEST(Septic, DerivativesMatchFiniteDifferencesAndRestAtBothEnds) {
  const double h = 1e-5;
  for (int k = 1; k < 100; ++k) {
    const double u = k / 100.0;
    const auto s = planners::septic(u), lo = planners::septic(u - h), hi = planners::septic(u + h);
    EXPECT_NEAR(s.ds, (hi.s - lo.s) / (2 * h), 1e-7) << u;
    EXPECT_NEAR(s.dds, (hi.ds - lo.ds) / (2 * h), 1e-6) << u;
    EXPECT_NEAR(s.ddds, (hi.dds - lo.dds) / (2 * h), 1e-5) << u;
    // Against the expanded polynomial 35u^4 - 84u^5 + 70u^6 - 20u^7.
    EXPECT_NEAR(s.s, 35 * std::pow(u, 4) - 84 * std::pow(u, 5) + 70 * std::pow(u, 6) - 20 * std::pow(u, 7), 1e-13);
  }
  const auto start = planners::septic(0.0), end = planners::septic(1.0);
  EXPECT_EQ(start.s, 0.0);
  EXPECT_EQ(end.s, 1.0);
  for (const auto& s : {start, end}) {
    EXPECT_EQ(s.ds, 0.0);
    EXPECT_EQ(s.dds, 0.0);
    EXPECT_EQ(s.ddds, 0.0);
  }
}

TEST(Septic, ProfileIsC3AcrossWaypointsAndItsDerivativesMatchFiniteDifferences) {
  const Vector7 a = Vector7::Zero(), b = (Vector7() << 0.5, -0.3, 0.2, -1.0, 0.1, 0.4, -0.6).finished();
  const Vector7 c = (Vector7() << -0.2, 0.1, 0.0, -1.5, 0.3, 1.0, 0.2).finished();
  const planners::TransferProfile profile({a, b, c}, {1.25, 0.8});
  EXPECT_DOUBLE_EQ(profile.duration(), 2.05);
  const double h = 1e-6;
  for (double t = 0.01; t < 2.05; t += 0.0137) {
    const auto s = profile.sample(t), lo = profile.sample(t - h), hi = profile.sample(t + h);
    EXPECT_TRUE(near(s.dq, (hi.q - lo.q) / (2 * h), 1e-6)) << t;
    EXPECT_TRUE(near(s.ddq, (hi.dq - lo.dq) / (2 * h), 1e-5)) << t;
    EXPECT_TRUE(near(s.dddq, (hi.ddq - lo.ddq) / (2 * h), 1e-4)) << t;
  }
  // At the waypoints: there, at rest, from both sides.
  for (const double t : {0.0, 1.25, 2.05}) {
    for (const double side : {-1e-9, 0.0, 1e-9}) {
      const auto s = profile.sample(t + side);
      EXPECT_TRUE(near(s.dq, Vector7::Zero(), 1e-12));
      EXPECT_TRUE(near(s.ddq, Vector7::Zero(), 1e-9));
      EXPECT_TRUE(near(s.dddq, Vector7::Zero(), 1e-4));
    }
  }
  EXPECT_EQ(profile.sample(0.0).q, a);
  EXPECT_EQ(profile.sample(1.25).q, b);
  EXPECT_EQ(profile.sample(2.05).q, c);
}

TEST(Septic, DurationIsTheClosedFormWhenAPeakBinds) {
  // One joint, a long slow move: only the velocity or acceleration peak can bind (no torque issue on joint 7).
  Model model = make_model("panda");
  const JointLimits& limits = model.parameters().joint_limits;
  Vector7 a;
  a << 0.0, -0.7853981633974483, 0.0, -2.356194490192345, 0.0, 1.5707963267948966, -2.0;
  Vector7 b = a;
  b[6] = 2.0;
  planners::TimingLimits fractions;
  fractions.tool_speed = 100.0;   // joint 7 hardly moves the TCP, but keep it out of the way
  const auto timed = planners::time_transfer({a, b}, model, fractions);
  const double velocity = 2.1875 * 4.0 / (0.6 * limits.dq_max[6]);
  const double acceleration = std::sqrt(7.5132 * 4.0 / (0.5 * limits.ddq_max[6]));
  const double jerk = std::cbrt(52.5 * 4.0 / (0.5 * limits.dddq_max[6]));
  const double expected = std::max({velocity, acceleration, jerk});
  ASSERT_EQ(timed.segments.size(), 1u);
  EXPECT_NEAR(timed.segments[0].duration, std::ceil(expected * 1000) / 1000, 1e-12);
  EXPECT_EQ(timed.segments[0].binding, velocity > acceleration ? "velocity" : "acceleration");
}

// ---------------- Re-checking a timed transfer at 1 kHz ----------------

struct TrajectoryCheck {
  double lowest_clearance = std::numeric_limits<double>::infinity();
  std::string lowest_pair;
  // Worst |value| / limit over samples and joints (the robot's full limits).
  double velocity = 0, acceleration = 0, jerk = 0, torque = 0, tool_speed = 0;
  double largest_step = 0;   // max |q(k+1) - q(k)| [rad]
};

TrajectoryCheck check_log(const JointLog& log, const Model& model, ClearanceChecker& checker, double tool_speed_limit) {
  TrajectoryCheck r;
  const JointLimits& limits = model.parameters().joint_limits;
  Data data;
  Vector3 previous_tcp = Vector3::Zero();
  for (std::size_t k = 0; k < log.size(); ++k) {
    const auto c = checker.check_all_pairs(log.q[k]);
    if (c.clearance < r.lowest_clearance) {
      r.lowest_clearance = c.clearance;
      r.lowest_pair = std::string(c.moving) + " vs " + std::string(c.other);
    }
    const Vector7 up = limits.position_based_velocity ? limits.dq_upper(log.q[k]) : limits.dq_max;
    const Vector7 down = limits.position_based_velocity ? limits.dq_lower(log.q[k]) : Vector7(-limits.dq_max);
    for (int j = 0; j < kNumJoints; ++j) {
      const double dq = log.dq[k][j];
      if (dq != 0.0) r.velocity = std::max(r.velocity, dq > 0 ? dq / up[j] : dq / down[j]);
      r.acceleration = std::max(r.acceleration, std::abs(log.ddq[k][j]) / limits.ddq_max[j]);
      r.torque = std::max(r.torque, std::abs(log.tau_J[k][j]) / limits.tau_max[j]);
    }
    forward_kinematics(model, data, log.q[k]);
    const Vector3 tcp = frame_pose(data, Frame::kEndEffector).translation;
    if (k > 0) {
      const double dt = log.t[k] - log.t[k - 1];
      r.tool_speed = std::max(r.tool_speed, (tcp - previous_tcp).norm() / dt / tool_speed_limit);
      r.largest_step = std::max(r.largest_step, (log.q[k] - log.q[k - 1]).cwiseAbs().maxCoeff());
      // Jerk from the log's accelerations (finite differences, not the profile's closed form).
      r.jerk = std::max(r.jerk, ((log.ddq[k] - log.ddq[k - 1]) / dt).cwiseQuotient(limits.dddq_max).cwiseAbs().maxCoeff());
    }
    previous_tcp = tcp;
  }
  return r;
}

// Every transfer between the named poses of each shipped scene, on Panda and FR3: planned, timed,
// sampled at 1 kHz; every sample collision-free against every pair and within the limit shares.
TEST(Transfer, EveryShippedTransferIsFreeAndWithinLimitsAt1kHz) {
  int transfers = 0;
  for (const auto& robot : kRobots)
    for (const auto& name : kScenes) {
      const Scene scene = load_scene(scene_file(name));
      const Model model = scene_model(robot, scene);
      ClearanceChecker checker(model, scene);
      for (const auto& from : scene.poses)
        for (const auto& to : scene.poses) {
          if (from.name == to.name) continue;
          SCOPED_TRACE(robot + " " + name + ": " + from.name + " -> " + to.name);
          const TransferPlan plan = planners::plan_transfer(scene, checker, model.parameters().joint_limits, from, to);
          ASSERT_TRUE(plan.found()) << plan.message;
          EXPECT_EQ(plan.waypoints.front(), from.q);
          EXPECT_EQ(plan.waypoints.back(), to.q);
          const planners::TimingLimits fractions;
          const auto timed = planners::time_transfer(plan.waypoints, model, fractions);
          const JointLog log = planners::trajectory_log(timed.profile, 1000.0, model);
          EXPECT_EQ(log.q.back(), to.q);
          const TrajectoryCheck r = check_log(log, model, checker, fractions.tool_speed);
          EXPECT_GE(r.lowest_clearance, 0.0) << r.lowest_pair;
          // Within the shares (the duration was set on a 1000-phase grid: a 1e-3 relative allowance).
          EXPECT_LE(r.velocity, fractions.velocity * 1.001);
          EXPECT_LE(r.acceleration, fractions.acceleration * 1.001);
          EXPECT_LE(r.jerk, fractions.jerk * 1.001);
          EXPECT_LE(r.torque, fractions.torque * 1.001);
          EXPECT_LE(r.tool_speed, 1.001);
          EXPECT_LT(r.largest_step, 0.01);
          // The certified margin along the 1 kHz path (the check's motion bound): at most the dense
          // minimum, and no state of its motion, re-sampled 100 times against every pair, goes below it.
          const planners::TrajectoryCheck checked = planners::check_trajectory(log, model, scene);
          EXPECT_LE(checked.certified_min_clearance, checked.dense_min_clearance);
          EXPECT_NEAR(checked.dense_min_clearance, r.lowest_clearance, 1e-12);
          EXPECT_GE(checked.certified_min_clearance, 0.0);
          const auto row = static_cast<std::size_t>(std::lround(checked.t_certified_min * 1000.0));
          ASSERT_LT(row + 1, log.size());
          for (int i = 0; i <= 100; ++i) {
            const Vector7 q = log.q[row] + (i / 100.0) * (log.q[row + 1] - log.q[row]);
            EXPECT_GE(checker.check_all_pairs(q).clearance, checked.certified_min_clearance - 1e-12);
          }
          std::string bindings;
          for (const auto& segment : timed.segments) bindings += (bindings.empty() ? "" : ",") + segment.binding;
          std::printf("%s %s %s -> %s: %zu waypoints, %.3f s (%s), lowest clearance %.4f m (%s), certified %.4f m\n",
                      robot.c_str(), name.c_str(), from.name.c_str(), to.name.c_str(), plan.waypoints.size(),
                      timed.profile.duration(), bindings.c_str(), r.lowest_clearance, r.lowest_pair.c_str(),
                      checked.certified_min_clearance);
          ++transfers;
        }
    }
  EXPECT_GE(transfers, static_cast<int>(2 * kRobots.size() * kScenes.size()));   // each scene has >= 2 poses
}

// ---------------- Random box scenes ----------------

struct RandomBoxScene {
  Scene scene;
  Vector7 start, goal;
};

// The ultrasound scene's floor and cart, plus six random boxes in the arm's workspace (clear of the
// base column, which links 0-2 cannot leave), and random valid start and goal states.
RandomBoxScene random_box_scene(std::mt19937_64& engine, const Scene& base, const Model& model, ClearanceChecker** checker_out,
                                std::unique_ptr<ClearanceChecker>& checker) {
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); };
  RandomBoxScene r;
  r.scene = base;
  r.scene.obstacles.erase(r.scene.obstacles.begin() + 2, r.scene.obstacles.end());
  const Capsule base_column{{0.0, 0.0, -0.1}, {0.0, 0.0, 0.45}, 0.15};
  for (int i = 0; i < 6; ++i) {
    Box b;
    const Eigen::Vector4d wxyz(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    b.pose.rotation = Eigen::Quaterniond(wxyz.normalized()).toRotationMatrix();
    b.half_size = {uniform(0.03, 0.15), uniform(0.03, 0.15), uniform(0.03, 0.15)};
    do b.pose.translation = Vector3(uniform(-0.7, 0.7), uniform(-0.7, 0.7), uniform(-0.2, 1.0));
    while (distance(base_column, b).distance < 0.05);
    r.scene.obstacles.push_back({"box" + std::to_string(i), "table", b, {}});
  }
  checker = std::make_unique<ClearanceChecker>(model, r.scene);
  *checker_out = checker.get();
  const JointLimits& limits = model.parameters().joint_limits;
  auto valid_state = [&] {
    for (int tries = 0; tries < 10000; ++tries) {
      Vector7 q;
      for (int j = 0; j < kNumJoints; ++j) q[j] = uniform(limits.q_min[j] + 0.05, limits.q_max[j] - 0.05);
      if (checker->is_valid(q)) return q;
    }
    throw std::runtime_error("no valid state in 10000 tries");
  };
  r.start = valid_state();
  r.goal = valid_state();
  return r;
}

// The path's straight segments re-sampled with joint steps of at most 1e-3 rad, every pair exactly.
double lowest_clearance_along(const std::vector<Vector7>& path, ClearanceChecker& checker) {
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Vector7 d = path[i + 1] - path[i];
    const int steps = std::max(1, static_cast<int>(std::ceil(d.cwiseAbs().maxCoeff() / 1e-3)));
    for (int s = 0; s <= steps; ++s) lowest = std::min(lowest, checker.check_all_pairs(path[i] + d * s / steps).clearance);
  }
  return lowest;
}

TEST(Transfer, RandomBoxScenesNeverGetAnInvalidPlan) {
  const Scene base = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", base);
  std::mt19937_64 engine(2026);
  int found = 0, detours = 0, not_found = 0;
  TransferOptions options;
  options.max_iterations = 2000;
  for (int i = 0; i < kRandomScenes; ++i) {
    SCOPED_TRACE("random scene " + std::to_string(i));
    std::unique_ptr<ClearanceChecker> owner;
    ClearanceChecker* checker = nullptr;
    const RandomBoxScene r = random_box_scene(engine, base, model, &checker, owner);
    options.seed = static_cast<std::uint64_t>(i + 1);
    const TransferPlan plan = planners::plan_transfer(r.scene, *checker, model.parameters().joint_limits,
                                                      {"start", r.start}, {"goal", r.goal}, options);
    if (!plan.found()) {
      ++not_found;
      EXPECT_TRUE(plan.waypoints.empty());
      EXPECT_NE(plan.message.find("no path found within 2000 iterations"), std::string::npos) << plan.message;
      if (!plan.best_attempt.empty()) {
        EXPECT_GE(lowest_clearance_along(plan.best_attempt, *checker), 0.0);
      }
      continue;
    }
    ++found;
    detours += plan.waypoints.size() > 2 ? 1 : 0;
    EXPECT_EQ(plan.waypoints.front(), r.start);
    EXPECT_EQ(plan.waypoints.back(), r.goal);
    EXPECT_GE(lowest_clearance_along(plan.waypoints, *checker), 0.0);
  }
  RecordProperty("found", found);
  RecordProperty("detours", detours);
  RecordProperty("not_found", not_found);
  std::printf("random box scenes: %d found (%d around obstacles), %d not found in the budget\n", found, detours, not_found);
  // Not vacuous: most are found, and some needed a path around the boxes.
  EXPECT_GE(found, kRandomScenes / 2);
  EXPECT_GE(detours, kRandomScenes / 10);
}

// ---------------- Determinism: the same seed, the same waypoints, in two processes ----------------

// A random box scene whose straight start-goal motion is blocked, so that the plan depends on OMPL's
// random samples.
struct DetourProblem {
  RandomBoxScene r;
  std::unique_ptr<ClearanceChecker> checker;
};
DetourProblem detour_problem(const Scene& base, const Model& model) {
  std::mt19937_64 engine(77);
  for (;;) {
    DetourProblem p;
    ClearanceChecker* checker = nullptr;
    p.r = random_box_scene(engine, base, model, &checker, p.checker);
    if (!checker->motion_is_free(p.r.start, p.r.goal)) return p;
  }
}

// The waypoints of the detour problem planned with `seed`, every double in hexadecimal (exact).
std::string detour_plan_text(std::uint64_t seed) {
  const Scene base = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", base);
  DetourProblem p = detour_problem(base, model);
  TransferOptions options;
  options.seed = seed;
  const TransferPlan plan = planners::plan_transfer(p.r.scene, *p.checker, model.parameters().joint_limits,
                                                    {"start", p.r.start}, {"goal", p.r.goal}, options);
  std::string text = plan.found() ? "found\n" : "not found: " + plan.message + "\n";
  for (const auto& q : plan.waypoints) {
    for (int j = 0; j < kNumJoints; ++j) {
      char number[40];
      std::snprintf(number, sizeof number, "%a%c", q[j], j + 1 < kNumJoints ? ' ' : '\n');
      text += number;
    }
  }
  return text;
}

std::string run_self(const std::string& arguments) {
  const std::string command = "/proc/" + std::to_string(::getpid()) + "/exe " + arguments;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("cannot run " + command);
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = ::pclose(pipe);
  if (status != 0) throw std::runtime_error(command + " exited with status " + std::to_string(status));
  return out;
}

TEST(Transfer, SameSeedGivesByteIdenticalWaypointsInTwoProcesses) {
  const std::string first = run_self("--print-detour-plan 7");
  const std::string second = run_self("--print-detour-plan 7");
  EXPECT_EQ(first, second);
  // In this process, after another plan (OMPL's RNGs already started): the same bytes.
  const std::string other_seed = detour_plan_text(8);
  const std::string here = detour_plan_text(7);
  EXPECT_EQ(here, first);
  ASSERT_EQ(here.rfind("found\n", 0), 0u) << here;
  EXPECT_GT(std::count(here.begin(), here.end(), '\n'), 3) << "a detour has a waypoint between start and goal";
  // Not vacuous: the seed matters.
  EXPECT_NE(other_seed, here);
}

// ---------------- Bad input and no plan ----------------

std::string transfer_error(const Scene& scene, ClearanceChecker& checker, const Model& model, const NamedPose& from,
                           const NamedPose& to, const TransferOptions& options = {}) {
  try {
    planners::plan_transfer(scene, checker, model.parameters().joint_limits, from, to, options);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(Transfer, StartInCollisionNamesThePair) {
  Scene scene = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", scene);
  // A ball where the ready pose's elbow (joint 4's frame) is.
  Data data;
  forward_kinematics(model, data, scene.pose("ready").q);
  scene.obstacles.push_back({"intruder", "equipment", Sphere{data.O_T_joint[3].translation, 0.03}, {}});
  scene.clearance["equipment"] = 0.05;
  ClearanceChecker checker(model, scene);
  const auto truth = checker.check_all_pairs(scene.pose("ready").q);
  ASSERT_LT(truth.clearance, 0.0);
  const std::string message = transfer_error(scene, checker, model, scene.pose("ready"), scene.pose("scan_start_hover"));
  EXPECT_NE(message.find("scene ultrasound_abdomen: start pose \"ready\" is in collision: "), std::string::npos) << message;
  EXPECT_NE(message.find(std::string(truth.moving) + " vs intruder (equipment)"), std::string::npos) << message;
  // The goal too, named as the goal.
  const std::string goal = transfer_error(scene, checker, model, scene.pose("scan_start_hover"), scene.pose("ready"));
  EXPECT_NE(goal.find("goal pose \"ready\" is in collision"), std::string::npos) << goal;
}

TEST(Transfer, BadRequestsGetOneClearError) {
  const Scene scene = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("fr3", scene);
  ClearanceChecker checker(model, scene);
  const NamedPose ready = scene.pose("ready"), hover = scene.pose("scan_start_hover");
  NamedPose high = ready;
  high.q[3] = -0.10;   // FR3's q_max[3] is -0.1169 (configs/robots/fr3.yaml): within the 0.05 rad margin
  high.name = "high";
  struct Case {
    std::string expected, got;
  };
  TransferOptions planner, seed, budget, margin;
  planner.planner = "prm";
  seed.seed = 0;
  budget.max_iterations = 0;
  margin.limit_margin = -1.0;
  const std::vector<Case> cases = {
      {"goal pose \"high\": joint 4 = -0.1 rad is outside [-3.027, -0.1669] (its limits minus the 0.05 rad margin)",
       transfer_error(scene, checker, model, ready, high)},
      {"planner \"prm\" is not one of rrtconnect, rrtstar, bitstar, lazyprmstar",
       transfer_error(scene, checker, model, ready, hover, planner)},
      {"seed = 0 is outside 1 .. 4294967295", transfer_error(scene, checker, model, ready, hover, seed)},
      {"max_iterations = 0 must be >= 1", transfer_error(scene, checker, model, ready, hover, budget)},
      {"limit_margin = -1 must be >= 0", transfer_error(scene, checker, model, ready, hover, margin)},
  };
  for (const auto& c : cases) EXPECT_NE(c.got.find(c.expected), std::string::npos) << "expected `" << c.expected << "` in: " << c.got;
}

TEST(Transfer, NothingFoundInTheBudgetSaysSoWithTheBestAttempt) {
  const Scene base = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", base);
  DetourProblem p = detour_problem(base, model);
  TransferOptions options;
  options.max_iterations = 2;
  const TransferPlan plan = planners::plan_transfer(p.r.scene, *p.checker, model.parameters().joint_limits,
                                                    {"start", p.r.start}, {"goal", p.r.goal}, options);
  EXPECT_FALSE(plan.found());
  EXPECT_TRUE(plan.waypoints.empty());
  EXPECT_TRUE(plan.cap_hit);
  EXPECT_EQ(plan.iterations, 2);
  EXPECT_NE(plan.message.find("no path found within 2 iterations of RRTConnect"), std::string::npos) << plan.message;
  if (!plan.best_attempt.empty()) {
    EXPECT_GT(plan.best_distance, 0.0);
    EXPECT_GE(lowest_clearance_along(plan.best_attempt, *p.checker), 0.0);
  }
}

TEST(Timing, InfeasibleLimitsGetOneClearError) {
  const Model model = make_model("panda");
  const Vector7 ready = (Vector7() << 0, -0.785, 0, -2.356, 0, 1.571, 0.785).finished();
  Vector7 other = ready;
  other[0] = 0.5;
  auto error = [&](const std::vector<Vector7>& waypoints, const planners::TimingLimits& limits) -> std::string {
    try {
      planners::time_transfer(waypoints, model, limits);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  };
  planners::TimingLimits weak;
  weak.torque = 0.05;
  EXPECT_NE(error({ready, other}, weak).find("against gravity alone"), std::string::npos) << error({ready, other}, weak);
  EXPECT_NE(error({ready, ready}, {}).find("waypoints 0 and 1 are equal"), std::string::npos);
  EXPECT_NE(error({ready}, {}).find("at least 2 waypoints"), std::string::npos);
  planners::TimingLimits too_much;
  too_much.velocity = 1.5;
  EXPECT_NE(error({ready, other}, too_much).find("velocity limit 1.5"), std::string::npos) << error({ready, other}, too_much);
  planners::TimingLimits rate;
  rate.torque_rate = 0.0;
  EXPECT_NE(error({ready, other}, rate).find("torque rate limit 0"), std::string::npos) << error({ready, other}, rate);
  planners::TimingLimits no_power;
  no_power.power = 1e-9;   // lifting against gravity: its power decays only as 1/T
  Vector7 lifted = ready;
  lifted[1] = -1.2;
  EXPECT_NE(error({ready, lifted}, no_power).find("the power stays above"), std::string::npos) << error({ready, lifted}, no_power);
}

// The torque rate and the power: moves whose peak-set timing would exceed them are stretched just
// enough, as the independent check (check_trajectory: RNEA on the 1 kHz log, the torque's backward
// differences, sum of positive joint powers) finds: within at the planned duration, over at 3 %
// less (the duration is rounded up to whole milliseconds: at most 1.3 % here), with the limit named
// as the binding one. The shares are the check's full limits here, so that "just enough" is
// measured against the check itself.
struct StretchCase {
  const char* name;
  Vector7 from, to;
  planners::TimingLimits limits;
  const char* binding;      // expected binding of the segment
  const char* check_kind;   // the check's failure kind at 3 % less
};

TEST(Timing, TorqueRateAndPowerAreStretchedJustEnoughAsTheCheckFindsAt1kHz) {
  Scene scene = load_scene(scene_file("ultrasound_abdomen"));
  scene.obstacles.clear();   // free space: the timing is on trial, not the geometry (self pairs stay)
  const Model model = scene_model("panda", scene);
  const JointLimits& limits = model.parameters().joint_limits;
  const Vector7 ready = (Vector7() << 0, -0.785, 0, -2.356, 0, 1.571, 0.785).finished();
  const Vector7 nudge = (Vector7() << 0.004, 0.004, 0, -0.004, 0, 0, 0).finished();   // a small correction
  const Vector7 swing = (Vector7() << 1.6, 0.6, 0, 0.9, 0, 0, 0).finished();            // shoulder, lift and elbow
  planners::TimingLimits full_rate;   // the robot's whole acceleration and jerk: a quick correction
  full_rate.acceleration = full_rate.jerk = full_rate.torque_rate = 1.0;
  full_rate.tool_speed = 100.0;
  planners::TimingLimits low_power;
  low_power.power = 10.0;
  low_power.tool_speed = 100.0;
  const StretchCase cases[] = {{"torque rate", ready, ready + nudge, full_rate, "torque rate", "torque_rate"},
                               {"power", ready, ready + swing, low_power, "power", "power"}};
  for (const StretchCase& c : cases) {
    SCOPED_TRACE(c.name);
    const auto timed = planners::time_transfer({c.from, c.to}, model, c.limits);
    ASSERT_EQ(timed.segments.size(), 1u);
    EXPECT_EQ(timed.segments[0].binding, c.binding);
    planners::CheckOptions options;
    options.power_limit = c.limits.power;
    options.tool_speed_limit = c.limits.tool_speed;
    const auto check = [&](double scale) {
      const planners::TransferProfile profile({c.from, c.to}, {timed.segments[0].duration * scale});
      return planners::check_trajectory(planners::trajectory_log(profile, 1000.0, model), model, scene, options);
    };
    const planners::TrajectoryCheck planned = check(1.0);
    for (const auto& failure : planned.failures) ADD_FAILURE() << planners::describe(failure);
    double rate = 0.0;
    for (const auto& joint : planned.joints) rate = std::max(rate, joint.torque_rate);
    const double used = std::string(c.binding) == "power" ? planned.peak_power / c.limits.power : rate;
    EXPECT_GT(used, 0.96);   // just enough: the 1 kHz peak is at the limit (whole milliseconds aside)
    const auto over = [&](const planners::TrajectoryCheck& r) {
      return std::any_of(r.failures.begin(), r.failures.end(), [&](const planners::CheckFailure& f) { return f.kind == c.check_kind; });
    };
    EXPECT_TRUE(over(check(0.97))) << "3 % faster than planned is still within the " << c.binding;
    // The peak-set duration alone (velocity, acceleration, jerk: the closed form) is over too.
    double peaks = 0.0;
    const Vector7 delta = (c.to - c.from).cwiseAbs();
    for (int j = 0; j < kNumJoints; ++j)
      peaks = std::max({peaks, planners::kSepticPeakVelocity * delta[j] / (c.limits.velocity * limits.dq_max[j]),
                        std::sqrt(planners::kSepticPeakAcceleration * delta[j] / (c.limits.acceleration * limits.ddq_max[j])),
                        std::cbrt(planners::kSepticPeakJerk * delta[j] / (c.limits.jerk * limits.dddq_max[j]))});
    EXPECT_TRUE(over(check(peaks / timed.segments[0].duration)));
    std::printf("%s: peak-set %.3f s, stretched to %.3f s (%s); 1 kHz check: %.4f of the limit\n", c.name, peaks,
                timed.segments[0].duration, timed.segments[0].binding.c_str(), used);
  }
}

// ---------------- The bridge on a joint-space problem with an exact oracle ----------------

// A wall in joint space: the box |q1| <= 0.2, q2 <= 1.0 (all other joints free), in [-1.5, 1.5]^7.
// A straight segment meets it iff the slab intervals of q1 and q2 overlap: an exact motion check.
bool in_wall(const ompl_bridge::Joints& q) { return std::abs(q[0]) <= 0.2 && q[1] <= 1.0; }
bool segment_misses_wall(const ompl_bridge::Joints& a, const ompl_bridge::Joints& b) {
  double enter = 0.0, leave = 1.0;
  auto slab = [&](double p, double d, double lo, double hi) {
    if (d == 0.0) {
      if (p < lo || p > hi) leave = -1.0;
      return;
    }
    double t0 = (lo - p) / d, t1 = (hi - p) / d;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
  };
  slab(a[0], b[0] - a[0], -0.2, 0.2);
  slab(a[1], b[1] - a[1], -1e9, 1.0);
  return enter > leave;
}

ompl_bridge::Request wall_request(const std::string& planner) {
  ompl_bridge::Request request;
  request.lower.fill(-1.5);
  request.upper.fill(1.5);
  request.start = {-0.8, 0, 0, 0, 0, 0, 0};
  request.goal = {0.8, 0, 0, 0, 0, 0, 0};
  request.planner = planner;
  request.max_iterations = 1000;   // the optimizing planners (RRT*, BIT*, LazyPRM*) use all of it
  return request;
}

ompl_bridge::Callbacks wall_callbacks() {
  return {[](const ompl_bridge::Joints& q) { return !in_wall(q); }, nullptr, segment_misses_wall};
}

TEST(OmplBridge, EveryPlannerGoesAroundTheWall) {
  for (const auto& name : ompl_bridge::planner_names()) {
    SCOPED_TRACE(name);
    const auto result = ompl_bridge::plan_transfer(wall_request(name), wall_callbacks());
    ASSERT_TRUE(result.solved) << result.message;
    EXPECT_EQ(result.waypoints.front(), wall_request(name).start);
    EXPECT_EQ(result.waypoints.back(), wall_request(name).goal);
    bool over = false;
    for (std::size_t i = 0; i < result.waypoints.size(); ++i) {
      over |= result.waypoints[i][1] > 1.0;
      if (i > 0) {   // dense re-sampling, not the oracle the planner used
        const auto& a = result.waypoints[i - 1];
        const auto& b = result.waypoints[i];
        for (int s = 0; s <= 1000; ++s) {
          ompl_bridge::Joints q;
          for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * s / 1000.0;
          ASSERT_FALSE(in_wall(q)) << "segment " << i;
        }
      }
    }
    EXPECT_TRUE(over) << "the path must pass over the wall (q2 > 1)";
  }
}

TEST(OmplBridge, NoPathWhenTheGoalIsWalledInAndTheBudgetRunsOut) {
  auto request = wall_request("rrtconnect");
  auto callbacks = wall_callbacks();
  // A shell 0.1 < |q - goal|_inf < 0.2 around the goal: reachable only through the shell.
  callbacks.is_valid = [&](const ompl_bridge::Joints& q) {
    double d = 0.0;
    for (std::size_t j = 0; j < q.size(); ++j) d = std::max(d, std::abs(q[j] - request.goal[j]));
    return !(d > 0.1 && d < 0.2);
  };
  callbacks.motion_is_free = [&](const ompl_bridge::Joints& a, const ompl_bridge::Joints& b) {
    for (int s = 0; s <= 200; ++s) {   // fine enough for a shell 0.1 thick in [-1.5, 1.5]^7
      ompl_bridge::Joints q;
      for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * s / 200.0;
      if (!callbacks.is_valid(q)) return false;
    }
    return true;
  };
  const auto result = ompl_bridge::plan_transfer(request, callbacks);
  EXPECT_FALSE(result.solved);
  EXPECT_TRUE(result.cap_hit);
  EXPECT_EQ(result.iterations, 1000);
  EXPECT_TRUE(result.waypoints.empty());
  EXPECT_NE(result.message.find("no path found within 1000 iterations"), std::string::npos) << result.message;
}

TEST(OmplBridge, MalformedRequestsThrowNamingTheField) {
  auto error = [](ompl_bridge::Request request, ompl_bridge::Callbacks callbacks) -> std::string {
    try {
      ompl_bridge::plan_transfer(request, callbacks);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  };
  auto no_motion = wall_callbacks();
  no_motion.motion_is_free = nullptr;
  EXPECT_NE(error(wall_request("rrtconnect"), no_motion).find("motion_is_free callback is missing"), std::string::npos);
  auto outside = wall_request("rrtconnect");
  outside.goal[2] = 2.0;
  EXPECT_NE(error(outside, wall_callbacks()).find("goal[2] = 2.000000 is outside the bounds"), std::string::npos)
      << error(outside, wall_callbacks());
  auto flat = wall_request("rrtconnect");
  flat.upper[5] = flat.lower[5];
  EXPECT_NE(error(flat, wall_callbacks()).find("bounds of joint 6 are not lower < upper"), std::string::npos);
  auto blocked = wall_request("rrtconnect");
  blocked.start = {0, 0, 0, 0, 0, 0, 0};
  EXPECT_NE(error(blocked, wall_callbacks()).find("the start [0, 0, 0, 0, 0, 0, 0] is invalid"), std::string::npos)
      << error(blocked, wall_callbacks());
  EXPECT_EQ(ompl_bridge::ompl_version(), "1.5.2");   // Debian 12's libompl-dev
}

}  // namespace
}  // namespace csp::test

// `--print-detour-plan SEED`: print the detour plan's waypoints and exit (the second process of
// Transfer.SameSeedGivesByteIdenticalWaypointsInTwoProcesses); otherwise the tests.
int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--print-detour-plan") {
    std::fputs(csp::test::detour_plan_text(std::stoull(argv[2])).c_str(), stdout);
    return 0;
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
