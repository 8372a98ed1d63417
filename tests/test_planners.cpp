// planners/ and dynamics' collision geometry against independent references: brute-force surface
// sampling, KDL's forward kinematics, finite differences, the closed-form rest conditions, Gaz et
// al.'s commanded velocities, and dense re-sampling of certified motions.
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/collision_world.hpp"
#include "csp/dynamics/geometry.hpp"
#include "csp/io/yaml_field.hpp"
#include "csp/planners/checker.hpp"
#include "csp/planners/fourier.hpp"
#include "csp/io/scene.hpp"
#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

using planners::ClearanceChecker;
using planners::FourierSeries;

const std::vector<std::string> kScenes = {"ultrasound_abdomen", "doppler_femoral", "mis_rcm", "craniotomy"};

std::string scene_file(const std::string& name) { return std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + name + ".yaml"; }

// ---------------- Geometry vs brute-force surface sampling ----------------

// Two unit vectors completing `axis` to an orthonormal basis.
void basis(const Vector3& axis, Vector3& u, Vector3& v) {
  u = axis.unitOrthogonal();
  v = axis.cross(u);
}

// Points on a capsule's surface: rings on the cylinder and on the two hemispherical caps.
std::vector<Vector3> capsule_surface(const Capsule& c, int rings, int around) {
  std::vector<Vector3> points;
  const Vector3 d = c.b - c.a;
  const Vector3 axis = d.norm() > 0 ? Vector3(d.normalized()) : Vector3::UnitZ();
  Vector3 u, v;
  basis(axis, u, v);
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < around; ++j) {
      const double phi = 2 * std::numbers::pi * j / around;
      points.push_back(c.a + d * i / rings + c.radius * (std::cos(phi) * u + std::sin(phi) * v));
    }
  for (const auto& [end, out] : {std::pair{c.a, Vector3(-axis)}, std::pair{c.b, axis}})
    for (int i = 1; i <= rings; ++i) {
      const double theta = 0.5 * std::numbers::pi * i / rings;   // from the equator to the pole
      for (int j = 0; j < around; ++j) {
        const double phi = 2 * std::numbers::pi * j / around;
        points.push_back(end + c.radius * (std::sin(theta) * out + std::cos(theta) * (std::cos(phi) * u + std::sin(phi) * v)));
      }
    }
  return points;
}

std::vector<Vector3> sphere_surface(const Sphere& s, int rings, int around) {
  return capsule_surface(Capsule{s.center, s.center, s.radius}, rings, around);
}

std::vector<Vector3> box_surface(const Box& b, int n) {
  std::vector<Vector3> points;
  for (int axis = 0; axis < 3; ++axis)
    for (const double side : {-1.0, 1.0})
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Vector3 local;
          local[axis] = side * b.half_size[axis];
          local[(axis + 1) % 3] = (2.0 * i / n - 1.0) * b.half_size[(axis + 1) % 3];
          local[(axis + 2) % 3] = (2.0 * j / n - 1.0) * b.half_size[(axis + 2) % 3];
          points.push_back(b.pose * local);
        }
  return points;
}

double min_pair_distance(const std::vector<Vector3>& a, const std::vector<Vector3>& b) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : a)
    for (const auto& q : b) best = std::min(best, (p - q).squaredNorm());
  return std::sqrt(best);
}

// Independent membership tests (inside or on the surface).
double point_segment_distance(const Vector3& p, const Vector3& a, const Vector3& b) {
  const Vector3 d = b - a;
  const double t = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}
bool inside(const Vector3& p, const Capsule& c) { return point_segment_distance(p, c.a, c.b) < c.radius; }
bool inside(const Vector3& p, const Sphere& s) { return (p - s.center).norm() < s.radius; }
bool inside(const Vector3& p, const Box& b) {
  const Vector3 local = b.pose.rotation.transpose() * (p - b.pose.translation);
  return (local.cwiseAbs() - b.half_size).maxCoeff() < 0.0;
}
double box_surface_residual(const Vector3& p, const Box& b) {   // 0 on the surface
  const Vector3 local = b.pose.rotation.transpose() * (p - b.pose.translation);
  return std::abs((local.cwiseAbs() - b.half_size).maxCoeff());
}

struct RandomShapes {
  explicit RandomShapes(unsigned seed) : engine(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); }
  Vector3 point(double extent) { return {uniform(-extent, extent), uniform(-extent, extent), uniform(-extent, extent)}; }
  Vector3 direction() {
    Vector3 v;
    do v = point(1.0);
    while (v.norm() < 0.1 || v.norm() > 1.0);
    return v.normalized();
  }
  Capsule capsule() {
    const Vector3 c = point(0.2), axis = direction();
    const double half = uniform(0.0, 0.15);
    return {c - half * axis, c + half * axis, uniform(0.01, 0.08)};
  }
  Sphere sphere() { return {point(0.2), uniform(0.01, 0.1)}; }
  Box box() {
    Box b;
    const Eigen::Vector4d wxyz(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    b.pose.rotation = Eigen::Quaterniond(wxyz.normalized()).toRotationMatrix();
    b.pose.translation = point(0.2);
    b.half_size = {uniform(0.02, 0.15), uniform(0.02, 0.15), uniform(0.02, 0.15)};
    return b;
  }
  std::mt19937_64 engine;
};

// The closest points lie on the two surfaces and are |distance| apart; brute force over sampled
// surface pairs can only find a larger distance (it is an upper bound), by at most the sampling
// `cover`; a negative distance (overlap) deeper than `cover` shows up as sampled points inside.
template <typename B>
void expect_matches_brute_force(const Capsule& a, const B& b, const std::vector<Vector3>& surface_b,
                                double on_b_residual, double cover, int case_index) {
  SCOPED_TRACE("case " + std::to_string(case_index));
  const Distance d = distance(a, b);
  EXPECT_NEAR((d.on_a - d.on_b).norm(), std::abs(d.distance), 1e-9);
  if (d.distance > 0.0) {   // apart: the witnesses are surface points (so the distance is attained)
    EXPECT_NEAR(point_segment_distance(d.on_a, a.a, a.b), a.radius, 1e-9);
    EXPECT_LT(on_b_residual, 1e-9);
  }

  const std::vector<Vector3> surface_a = capsule_surface(a, 24, 48);
  const double brute = min_pair_distance(surface_a, surface_b);
  bool overlap_seen = false;
  for (const auto& p : surface_a) overlap_seen |= inside(p, b);
  for (const auto& p : surface_b) overlap_seen |= inside(p, a);
  if (d.distance > 0.0) {
    EXPECT_LE(d.distance, brute + 1e-12);
    EXPECT_GE(d.distance, brute - cover);
    EXPECT_FALSE(overlap_seen) << "distance " << d.distance << " but sampled points overlap";
  }
  if (d.distance < -cover) {
    EXPECT_TRUE(overlap_seen) << "distance " << d.distance << " but no sampled overlap";
  }
}

TEST(Geometry, CapsuleCapsuleMatchesBruteForceSurfaceSampling) {
  RandomShapes random(11);
  for (int k = 0; k < fewer_when_sanitized(80, 10); ++k) {
    const Capsule a = random.capsule(), b = random.capsule();
    const Distance d = distance(a, b);
    expect_matches_brute_force(a, b, capsule_surface(b, 24, 48), std::abs(point_segment_distance(d.on_b, b.a, b.b) - b.radius),
                               0.004, k);
  }
}

TEST(Geometry, CapsuleSphereMatchesBruteForceSurfaceSampling) {
  RandomShapes random(12);
  for (int k = 0; k < fewer_when_sanitized(80, 10); ++k) {
    const Capsule a = random.capsule();
    const Sphere b = random.sphere();
    const Distance d = distance(a, b);
    expect_matches_brute_force(a, b, sphere_surface(b, 24, 48), std::abs((d.on_b - b.center).norm() - b.radius), 0.004, k);
  }
}

TEST(Geometry, CapsuleBoxMatchesBruteForceSurfaceSampling) {
  RandomShapes random(13);
  for (int k = 0; k < fewer_when_sanitized(80, 10); ++k) {
    const Capsule a = random.capsule();
    const Box b = random.box();
    const Distance d = distance(a, b);
    expect_matches_brute_force(a, b, box_surface(b, 40), box_surface_residual(d.on_b, b), 0.006, k);
  }
}

TEST(Geometry, CapsuleHalfSpaceIsTheLowestSampledSurfacePoint) {
  RandomShapes random(14);
  for (int k = 0; k < 200; ++k) {
    const Capsule a = random.capsule();
    const HalfSpace h{random.point(0.2), random.direction()};
    const Distance d = distance(a, h);
    double lowest = std::numeric_limits<double>::infinity();   // signed height of the capsule's surface points
    for (const auto& p : capsule_surface(a, 24, 48)) lowest = std::min(lowest, h.normal.dot(p - h.point));
    EXPECT_LE(d.distance, lowest + 1e-12);
    EXPECT_GE(d.distance, lowest - 0.002);
    EXPECT_NEAR(h.normal.dot(d.on_b - h.point), 0.0, 1e-12);
    EXPECT_NEAR((d.on_a - d.on_b).norm(), std::abs(d.distance), 1e-12);
  }
}

TEST(Geometry, SegmentClosestPointsBeatDenseParameterSampling) {
  RandomShapes random(15);
  for (int k = 0; k < fewer_when_sanitized(200, 25); ++k) {
    const Capsule a = random.capsule(), b = random.capsule();
    const SegmentClosestPoints c = closest_points_segment_segment(a.a, a.b, b.a, b.b);
    double brute = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 400; ++i)
      for (int j = 0; j <= 400; ++j)
        brute = std::min(brute, (a.a + (a.b - a.a) * i / 400.0 - b.a - (b.b - b.a) * j / 400.0).norm());
    EXPECT_LE((c.c1 - c.c2).norm(), brute + 1e-12);
    EXPECT_GE((c.c1 - c.c2).norm(), brute - 0.3 / 400);   // segment lengths <= 0.3
  }
  // Parallel and degenerate segments.
  const auto parallel = closest_points_segment_segment({0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {2, 1, 0});
  EXPECT_NEAR((parallel.c1 - parallel.c2).norm(), 1.0, 1e-15);
  const auto points = closest_points_segment_segment({0, 0, 0}, {0, 0, 0}, {0, 3, 4}, {0, 3, 4});
  EXPECT_NEAR((points.c1 - points.c2).norm(), 5.0, 1e-15);
}

TEST(Geometry, BoundingBoxDistanceIsALowerBound) {
  RandomShapes random(16);
  for (int k = 0; k < 500; ++k) {
    const Capsule a = random.capsule();
    const Box b = random.box();
    const Sphere s = random.sphere();
    EXPECT_LE(distance_lower_bound(bounding_box(a), bounding_box(b)), std::max(distance(a, b).distance, 0.0) + 1e-12);
    EXPECT_LE(distance_lower_bound(bounding_box(a), bounding_box(s)), std::max(distance(a, s).distance, 0.0) + 1e-12);
  }
}

// ---------------- Capsules placed by forward kinematics vs KDL ----------------

TEST(Geometry, CapsulePlacementMatchesKdlForwardKinematics) {
  const Model model = make_model("panda");
  KdlPeer kdl(model);
  Data data;
  RandomStates random(21);
  for (int k = 0; k < 1000; ++k) {
    const Vector7 q = random.q(model.parameters().joint_limits);
    forward_kinematics(model, data, q);
    const auto frames = kdl.frame_poses(q);   // joint frames 1..7, flange, EE
    auto kdl_pose = [&](CapsuleFrame f) { return f == CapsuleFrame::kBase ? Transform{} : frames[static_cast<int>(f) - 1]; };
    auto expect_same = [&](const LinkCapsule& c) {
      const Capsule ours = placed(c.capsule, capsule_frame_pose(data, c.frame));
      const Transform T = kdl_pose(c.frame);
      EXPECT_TRUE(near(ours.a, T * c.capsule.a, 1e-12)) << c.name;
      EXPECT_TRUE(near(ours.b, T * c.capsule.b, 1e-12)) << c.name;
    };
    for (const auto& c : franka_arm_capsules()) expect_same(c);
    for (const auto& c : franka_hand_capsules()) expect_same(c);
  }
}

TEST(Geometry, ReachBoundsTheMotionOfEveryCapsulePoint) {
  // A joint step dq moves each capsule point by at most sum_j R_j |dq_j| (the motion check's bound).
  const Model model = make_model("panda");
  Data data;
  RandomStates random(22);
  for (int k = 0; k < 500; ++k) {
    const Vector7 q = random.q(model.parameters().joint_limits), step = random.uniform(0.05);
    for (const auto& c : franka_arm_capsules()) {
      double bound = 0.0;
      for (int j = 1; j <= kNumJoints; ++j) bound += reach_from_joint(model, j, c.frame, c.capsule) * std::abs(step[j - 1]);
      // The points of the capsule surface at both configurations (endpoints +- radius along an axis).
      forward_kinematics(model, data, q);
      const Transform before = capsule_frame_pose(data, c.frame);
      forward_kinematics(model, data, q + step);
      const Transform after = capsule_frame_pose(data, c.frame);
      for (const Vector3& end : {c.capsule.a, c.capsule.b})
        for (const Vector3& offset : {Vector3(c.capsule.radius, 0, 0), Vector3(0, c.capsule.radius, 0), Vector3(0, 0, c.capsule.radius)})
          EXPECT_LE((after * (end + offset) - before * (end + offset)).norm(), bound + 1e-12) << c.name;
    }
  }
}

// ---------------- The collision world (planner's clearance and emulator's contact) ----------------

// The arm's capsules, then one tool capsule on the flange.
std::vector<FrameCapsule> arm_and_probe() {
  Tool tool;
  tool.capsules.push_back({"probe", {Vector3(0.0, 0.0, 0.02), Vector3(0.0, 0.0, 0.1), 0.02}});
  return arm_and_tool_capsules(tool);
}

TEST(CollisionWorld, PairsEveryCapsuleWithEveryObstacleButItsExemptOnesGroupedByCapsule) {
  const std::vector<FrameCapsule> capsules = arm_and_probe();
  const CollisionWorld world(capsules, {{"cart", Sphere{Vector3(0.5, 0.0, 0.0), 0.1}, {"link0", "probe"}},
                                        {"floor", HalfSpace{}, {}}});
  std::vector<std::array<int, 2>> expected;
  for (int c = 0; c < static_cast<int>(capsules.size()); ++c) {
    if (capsules[c].name != "link0" && capsules[c].name != "probe") expected.push_back({c, 0});
    expected.push_back({c, 1});
  }
  ASSERT_EQ(world.pairs().size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(world.pairs()[k].capsule, expected[k][0]) << k;
    EXPECT_EQ(world.pairs()[k].obstacle, expected[k][1]) << k;
  }
  // The sphere's box is its centre +- radius; the half-space has none.
  ASSERT_TRUE(world.obstacle_box(0).has_value());
  EXPECT_TRUE(near(world.obstacle_box(0)->min, Vector3(0.4, -0.1, -0.1), 1e-15));
  EXPECT_TRUE(near(world.obstacle_box(0)->max, Vector3(0.6, 0.1, 0.1), 1e-15));
  EXPECT_FALSE(world.obstacle_box(1).has_value());
}

TEST(CollisionWorld, PlacesCapsulesWhereTheHandComputedFramesPutThem) {
  // q1 = pi/2, the rest 0: link 1's frame is the base frame turned a quarter about z and lifted by
  // d1 = 0.333 m, so (x, y, z) lands at (-y, x, z + 0.333). The flange sits at a4 + a5 + a7 =
  // 0.0825 - 0.0825 + 0.088 m along the base y axis (x at q = 0, turned with joint 1), at height
  // d1 + d3 + d5 - d_flange = 0.333 + 0.316 + 0.384 - 0.107 = 0.926 m, its z axis pointing down.
  const Model model = make_model("panda");
  Data data;
  Vector7 q = Vector7::Zero();
  q[0] = std::numbers::pi / 2;
  forward_kinematics(model, data, q);
  const CollisionWorld world(arm_and_probe(), {});
  std::vector<Capsule> placed_capsules;
  std::vector<Aabb> boxes;
  world.place(data, placed_capsules, boxes);
  ASSERT_EQ(placed_capsules.size(), world.capsules().size());

  const Capsule& link1_local = world.capsules()[1].local;
  auto on_link1 = [](const Vector3& p) { return Vector3(-p.y(), p.x(), p.z() + 0.333); };
  EXPECT_TRUE(near(placed_capsules[1].a, on_link1(link1_local.a), 1e-12));
  EXPECT_TRUE(near(placed_capsules[1].b, on_link1(link1_local.b), 1e-12));
  EXPECT_EQ(placed_capsules[1].radius, link1_local.radius);

  const Capsule& probe = placed_capsules[kNumArmCapsules];
  EXPECT_TRUE(near(probe.a, Vector3(0.0, 0.088, 0.906), 1e-12));
  EXPECT_TRUE(near(probe.b, Vector3(0.0, 0.088, 0.826), 1e-12));
  EXPECT_TRUE(near(boxes[kNumArmCapsules].min, Vector3(-0.02, 0.068, 0.806), 1e-12));
  EXPECT_TRUE(near(boxes[kNumArmCapsules].max, Vector3(0.02, 0.108, 0.926), 1e-12));
  // The one-capsule placement the contact engine uses is the same.
  EXPECT_TRUE(near(world.placed_capsule(data, kNumArmCapsules).a, probe.a, 0.0));
}

TEST(CollisionWorld, SceneWorldHasTheScenesCapsulesObstaclesAndExemptions) {
  for (const std::string& name : kScenes) {
    const Scene scene = load_scene(scene_file(name));
    const CollisionWorld world = collision_world(scene);
    ASSERT_EQ(world.capsules().size(), kNumArmCapsules + scene.tool.capsules.size()) << name;
    ASSERT_EQ(world.obstacles().size(), scene.obstacles.size()) << name;
    std::size_t pairs = 0;
    for (std::size_t o = 0; o < scene.obstacles.size(); ++o) {
      EXPECT_EQ(world.obstacles()[o].name, scene.obstacles[o].name);
      pairs += world.capsules().size() - scene.obstacles[o].exempt.size();   // load_scene: exempt names are capsules
    }
    EXPECT_EQ(world.pairs().size(), pairs) << name;
  }
}

// ---------------- Fourier series ----------------

FourierSeries random_rest_to_rest(unsigned seed, const Vector7& anchor) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  Eigen::MatrixXd free(kNumJoints, 7);   // N = 5: 2N - 3 = 7 free coefficients per joint
  for (int i = 0; i < free.size(); ++i) free(i) = uniform(engine);
  return FourierSeries::rest_to_rest(0.1, 5, free, anchor);
}

TEST(Fourier, DerivativesMatchCentralDifferences) {
  const FourierSeries series = random_rest_to_rest(31, Vector7::Constant(0.3));
  const double h = 1e-5;
  for (double t = 0.0; t < 25.0; t += 0.37) {
    const auto s = series.sample(t), plus = series.sample(t + h), minus = series.sample(t - h);
    EXPECT_TRUE(near(s.dq, (plus.q - minus.q) / (2 * h), 1e-8)) << "t " << t;
    EXPECT_TRUE(near(s.ddq, (plus.dq - minus.dq) / (2 * h), 1e-8)) << "t " << t;
    EXPECT_TRUE(near(s.dddq, (plus.ddq - minus.ddq) / (2 * h), 1e-8)) << "t " << t;
  }
}

TEST(Fourier, RestAtTheAnchorAtEveryPeriodEnd) {
  const Vector7 anchor = (Vector7() << 0.1, -0.7, 0.2, -2.1, 0.0, 1.6, 0.8).finished();
  for (unsigned seed : {32u, 33u, 34u}) {
    const FourierSeries series = random_rest_to_rest(seed, anchor);
    ASSERT_GT(series.a().cwiseAbs().maxCoeff(), 0.05);   // a real motion, not a zero series
    for (int k = 0; k <= 5; ++k) {
      const auto s = series.sample(k * series.period());
      EXPECT_TRUE(near(s.q, anchor, 1e-12)) << "period " << k;
      EXPECT_TRUE(near(s.dq, Vector7::Zero(), 1e-12)) << "period " << k;
      EXPECT_TRUE(near(s.ddq, Vector7::Zero(), 1e-12)) << "period " << k;
      EXPECT_TRUE(near(s.dddq, Vector7::Zero(), 1e-12)) << "period " << k;
    }
  }
  EXPECT_EQ(planners::rest_to_rest_basis(5).cols(), 7);
  EXPECT_THROW(planners::rest_to_rest_basis(1), std::invalid_argument);
}

TEST(Fourier, BoundsHoldOverDenseSamplingAndAreReached) {
  const FourierSeries series = random_rest_to_rest(35, Vector7::Zero());
  const auto bounds = series.bounds();
  Vector7 q = Vector7::Zero(), dq = Vector7::Zero(), ddq = Vector7::Zero(), dddq = Vector7::Zero();
  for (double t = 0.0; t <= series.period(); t += 1e-3) {
    const auto s = series.sample(t);
    q = q.cwiseMax((s.q - series.q0()).cwiseAbs());
    dq = dq.cwiseMax(s.dq.cwiseAbs());
    ddq = ddq.cwiseMax(s.ddq.cwiseAbs());
    dddq = dddq.cwiseMax(s.dddq.cwiseAbs());
  }
  EXPECT_TRUE((q.array() <= bounds.q_deviation.array()).all());
  EXPECT_TRUE((dq.array() <= bounds.dq.array()).all());
  EXPECT_TRUE((ddq.array() <= bounds.ddq.array()).all());
  EXPECT_TRUE((dddq.array() <= bounds.dddq.array()).all());
  EXPECT_TRUE((dq.array() >= 0.3 * bounds.dq.array()).all());   // the bound is not vacuous
}

std::vector<double> read_numbers(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

TEST(Fourier, RegeneratesGazTrajectoryOneCommandedVelocities) {
  // ../shared/data/real/gaz2019_trajectory_1/SOURCE.md: rows 1-7 a, rows 8-14 b, w_f = 0.15 pi;
  // the series starts at t1 = 0.502 s, after the 0.5 s velocity ramp.
  const std::string dir = std::string(CSP_SHARED_DATA_DIR) + "/real/gaz2019_trajectory_1/";
  const std::vector<double> params = read_numbers(dir + "gen_params.txt");
  const std::vector<double> time = read_numbers(dir + "gen_time.txt");
  const std::vector<double> dq = read_numbers(dir + "gen_dq.txt");
  ASSERT_EQ(params.size(), 70u);
  ASSERT_EQ(dq.size(), 7 * time.size());
  planners::Coefficients a(kNumJoints, 5), b(kNumJoints, 5);
  for (int j = 0; j < kNumJoints; ++j)
    for (int l = 0; l < 5; ++l) {
      a(j, l) = params[j * 5 + l];
      b(j, l) = params[(j + 7) * 5 + l];
    }
  const FourierSeries series(0.075, a, b, Vector7::Zero());   // w_f = 0.15 pi = 2 pi 0.075
  // Tolerance from the printed precision: 10 coefficients rounded to 1e-4 (5e-5 each), stamps
  // rounded to 1e-4 s (5e-5 s times the acceleration bound), velocities to 1e-6.
  const Vector7 tolerance = Vector7::Constant(10 * 5e-5 + 5e-7) + 5e-5 * series.bounds().ddq;
  Vector7 worst = Vector7::Zero();
  int compared = 0;
  for (std::size_t k = 0; k < time.size(); ++k) {
    if (time[k] < 1.0 || time[k] > 20.0) continue;   // outside the ramps
    const Vector7 ours = series.sample(time[k] - 0.502).dq;
    for (int j = 0; j < kNumJoints; ++j) worst[j] = std::max(worst[j], std::abs(ours[j] - dq[7 * k + j]));
    ++compared;
  }
  EXPECT_GT(compared, 18000);
  EXPECT_TRUE((worst.array() <= tolerance.array()).all()) << "worst " << worst.transpose() << "\ntolerance " << tolerance.transpose();
}

// The trajectory as a joint log: sampled at the rate asked, and its tau_J is the torque the motion
// needs on the model (checked against the KDL peer's inverse dynamics plus the friction law).
TEST(Fourier, TrajectoryIsAJointLogWithTheTorqueItNeeds) {
  const FourierSeries series = random_rest_to_rest(36, Vector7::Constant(0.2));
  const Model model = make_model("panda");
  const JointLog log = planners::trajectory_log(series, 2.0, 1000.0, model);
  const std::string path = (temp_dir() / "excitation.csv").string();
  write_joint_log_csv(path, log);
  const JointLog read = read_joint_log_csv(path);
  ASSERT_EQ(read.size(), 2001u);
  EXPECT_DOUBLE_EQ(read.t.back(), 2.0);
  ASSERT_EQ(read.ddq.size(), 2001u);
  KdlPeer kdl(model);
  for (std::size_t k : {std::size_t{0}, std::size_t{777}, std::size_t{2000}}) {
    const planners::JointSample s = series.sample(read.t[k]);
    EXPECT_EQ(read.q[k], s.q);
    const Vector7 expected = kdl.rnea(s.q, s.dq, s.ddq) + friction_torque(model.parameters().friction, s.dq);
    EXPECT_LT((read.tau_J[k] - expected).cwiseAbs().maxCoeff(), 1e-9) << "row " << k;
  }
}

// ---------------- Scenes ----------------

Model scene_model(const std::string& robot, const Scene& scene) {
  return Model(with_tool(model_parameters(load_robot_config(robot_file(robot)), {}), scene.tool));
}

TEST(Scenes, EveryShippedSceneLoadsAndItsPosesAreCollisionFreeWithinLimits) {
  for (const std::string robot : {"panda", "fr3"})
    for (const auto& name : kScenes) {
      SCOPED_TRACE(robot + " " + name);
      const Scene scene = load_scene(scene_file(name));
      EXPECT_EQ(scene.name, name);
      const Model model = scene_model(robot, scene);
      ClearanceChecker checker(model, scene);
      const JointLimits& limits = model.parameters().joint_limits;
      EXPECT_GE(checker.check(scene.pose(scene.start).q).clearance, 0.0);
      for (const auto& pose : scene.poses) {
        const auto c = checker.check(pose.q);
        EXPECT_GE(c.clearance, 0.0) << pose.name << ": " << c.moving << " vs " << c.other << " (" << c.obstacle_class << ")";
        EXPECT_TRUE((pose.q.array() >= limits.q_min.array()).all() && (pose.q.array() <= limits.q_max.array()).all())
            << pose.name;
      }
    }
}

TEST(Scenes, HoverPosesPlaceTheToolWhereTheTaskSays) {
  // The `ik:` poses, re-derived by forward kinematics: TCP retracted along the tool axis from the task.
  Data data;
  auto tcp = [&](const Scene& scene, const std::string& pose) {
    const Model model = scene_model("panda", scene);
    forward_kinematics(model, data, scene.pose(pose).q);
    return data.O_T_EE;
  };
  for (const std::string name : {"ultrasound_abdomen", "doppler_femoral"}) {
    const Scene scene = load_scene(scene_file(name));
    const auto& scan = std::get<UltrasoundScan>(scene.task);
    for (const auto& [pose, point] : {std::pair{"scan_start_hover", scan.start}, std::pair{"scan_end_hover", scan.end}}) {
      const Transform T = tcp(scene, pose);
      EXPECT_TRUE(near(T.translation, point - scan.hover * scan.tool_axis, 1e-6)) << name << " " << pose;
      EXPECT_TRUE(near(T.rotation.col(2), scan.tool_axis, 1e-6)) << name << " " << pose;
    }
  }
  {
    const Scene scene = load_scene(scene_file("mis_rcm"));
    const auto& rcm = std::get<RcmPivot>(scene.task);
    const Transform T = tcp(scene, "port_hover");
    EXPECT_TRUE(near(T.translation, rcm.trocar + rcm.hover * Vector3::UnitZ(), 1e-6));
    EXPECT_TRUE(near(T.rotation.col(2), Vector3(-Vector3::UnitZ()), 1e-6));
  }
  {
    const Scene scene = load_scene(scene_file("craniotomy"));
    const auto& burr = std::get<BurrHole>(scene.task);
    const Transform T = tcp(scene, "burr_hover");
    EXPECT_TRUE(near(T.translation, burr.entry + 0.06 * burr.axis, 1e-6));
    EXPECT_TRUE(near(T.rotation.col(2), Vector3(-burr.axis), 1e-6));
    // The entry point is on the skull sphere.
    const auto& skull = std::get<Sphere>(std::find_if(scene.obstacles.begin(), scene.obstacles.end(), [](const auto& o) {
                                            return o.name == "skull";
                                          })->shape);
    EXPECT_NEAR((burr.entry - skull.center).norm(), skull.radius, 1e-9);
  }
}

TEST(Scenes, BroadPhaseFindsTheSamePairAsAllPairs) {
  for (const auto& name : kScenes) {
    const Scene scene = load_scene(scene_file(name));
    const Model model = scene_model("panda", scene);
    ClearanceChecker checker(model, scene);
    RandomStates random(41);
    for (int k = 0; k < 2000; ++k) {
      const Vector7 q = random.q(model.parameters().joint_limits);
      const auto fast = checker.check(q);
      const auto all = checker.check_all_pairs(q);
      ASSERT_EQ(fast.clearance, all.clearance) << name;
      EXPECT_EQ(fast.moving, all.moving);
      EXPECT_EQ(fast.other, all.other);
    }
  }
}

TEST(Scenes, DetectsObstacleAndSelfCollisions) {
  const Scene scene = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", scene);
  ClearanceChecker checker(model, scene);
  // Shoulder bent forward and down: the arm sweeps through the table and the patient.
  const Vector7 down = (Vector7() << 0.0, 1.2, 0.0, -0.3, 0.0, 1.5, 0.0).finished();
  const auto c = checker.check(down);
  EXPECT_LT(c.clearance, 0.0);
  EXPECT_NE(c.obstacle_class, "self");
  // Elbow folded completely with the wrist turned in: links 6-7 against link 2's neighbourhood.
  const Vector7 folded = (Vector7() << 0.0, -1.7, 0.0, -3.0, 0.0, 0.2, 0.0).finished();
  const auto s = checker.check(folded);
  EXPECT_LT(s.clearance, 0.0);
  EXPECT_EQ(s.obstacle_class, "self") << s.moving << " vs " << s.other;
}

// Writes `text` as a scene file and returns the error message of loading it.
std::string load_error(const std::string& text, const std::string& name) {
  const std::string path = (temp_dir() / (name + ".yaml")).string();
  std::ofstream(path) << text;
  try {
    load_scene(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string edited_scene(const std::string& from, const std::string& to) {
  std::ifstream in(scene_file("ultrasound_abdomen"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("ultrasound_abdomen.yaml no longer contains `" + from + "`");
  return text.replace(at, from.size(), to);
}

TEST(Scenes, InvalidScenesGetOneErrorNamingFileKeyAndExpectation) {
  struct Case {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
      {"    class: patient\n    source: \"assumption: head", "    class: patients\n    source: \"assumption: head",
       "obstacles[5].class: expected an obstacle class with a clearance in `clearance`"},
      {"exempt: [link0, link1]", "exempt: [link0, lnk1]", "obstacles[1].exempt[1]: expected the name of an arm or tool capsule"},
      {"max: [0.15, 0.25, 0.0]", "max: [0.15, -0.3, 0.0]", "obstacles[1].box.max: expected max > min on every axis"},
      {"normal: [0.0, 0.0, 1.0]", "normal: [0.0, 0.0, 2.0]", "obstacles[0].half_space.normal: expected a unit vector"},
      {"radius: 0.10}", "radius: 0.10, centre: [0, 0, 0]}", "obstacles[5].sphere.centre: expected no such key"},
      {"start: ready", "start: home", "start: expected the name of a pose in `poses`"},
      {"type: ultrasound_scan", "type: ultrasound", "task.type: expected ultrasound_scan, rcm_pivot or burr_hole"},
      {"  self: 0.02\n", "", "clearance: expected a `self` clearance"},
      {"speed: 0.02", "speed: -0.02", "task.speed: expected a positive number"},
      {"mass: 0.5", "mass: heavy", "tool.mass: expected a number"},
      {"    source: \"libfranka examples'", "    source: \"\"\n    note: \"libfranka examples'",
       "poses.ready.note: expected no such key"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const std::string name = "bad_scene_" + std::to_string(k++);
    const std::string message = load_error(edited_scene(c.from, c.to), name);
    EXPECT_NE(message.find(name + ".yaml: "), std::string::npos) << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << "expected `" << c.expected << "` in: " << message;
  }
  EXPECT_NE(load_error("name: [unclosed", "bad_yaml").find("bad_yaml.yaml: not valid YAML"), std::string::npos);
  try {
    load_scene("/nonexistent/scene.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml: cannot open the scene file"), std::string::npos);
  }
}

// ---------------- Certified motion check ----------------

TEST(MotionCheck, NeverCertifiesAMotionThatDenseResamplingFindsInCollision) {
  const Scene base = load_scene(scene_file("ultrasound_abdomen"));
  const Model model = scene_model("panda", base);
  int certified = 0, refused = 0, refused_colliding = 0;
  // Under the sanitizers the first five scenes, and more (up to all ten) until one refuses a motion
  // that collides (in Release scenes 4, 6 and 7 do; the sanitized build's SSE2 rounding may differ).
  const int scenes = fewer_when_sanitized(10, 5);
  for (int scene_index = 0; scene_index < 10 && (scene_index < scenes || refused_colliding == 0); ++scene_index) {
    RandomShapes shapes(51 + 2 * static_cast<unsigned>(scene_index));   // each scene its own draws
    RandomStates random(52 + 2 * static_cast<unsigned>(scene_index));
    Scene scene = base;
    scene.obstacles.erase(scene.obstacles.begin() + 2, scene.obstacles.end());   // keep floor and cart
    // Random boxes in the arm's workspace, clear of the base column (links 0-2 cannot move away from them).
    const Capsule base_column{{0.0, 0.0, -0.1}, {0.0, 0.0, 0.45}, 0.15};
    for (int i = 0; i < 6; ++i) {
      Box b = shapes.box();
      do b.pose.translation = Vector3(shapes.uniform(-0.7, 0.7), shapes.uniform(-0.7, 0.7), shapes.uniform(-0.2, 1.0));
      while (distance(base_column, b).distance < 0.05);
      scene.obstacles.push_back({"box" + std::to_string(i), "table", b, {}});
    }
    ClearanceChecker checker(model, scene);
    for (int m = 0; m < 15; ++m) {
      Vector7 q_a = random.q(model.parameters().joint_limits);
      for (int tries = 0; tries < 1000 && !checker.is_valid(q_a); ++tries) q_a = random.q(model.parameters().joint_limits);
      if (!checker.is_valid(q_a)) continue;
      const Vector7 q_b = q_a + random.uniform(0.4);
      if (!checker.is_valid(q_b)) continue;
      const bool free = checker.motion_is_free(q_a, q_b);
      // Dense: joint steps of at most 1e-4 rad (5e-4 under the sanitizers), every state against every pair.
      const double dense_step = kSanitized ? 5e-4 : 1e-4;
      const int steps = static_cast<int>(std::ceil((q_b - q_a).cwiseAbs().maxCoeff() / dense_step));
      double lowest = std::numeric_limits<double>::infinity();
      for (int s = 0; s <= steps; ++s)
        lowest = std::min(lowest, checker.check_all_pairs(q_a + (q_b - q_a) * s / steps).clearance);
      if (free) {
        ++certified;
        EXPECT_GE(lowest, 0.0) << "certified, but a dense state collides (scene " << scene_index << ", motion " << m << ")";
      } else {
        ++refused;
        refused_colliding += lowest < 0.0 ? 1 : 0;
      }
    }
  }
  // Not vacuous: most valid motions are certified, and the refused ones include real collisions.
  EXPECT_GT(certified, 3 * scenes);
  EXPECT_GT(refused_colliding, 0);
  RecordProperty("certified", certified);
  RecordProperty("refused", refused);
  RecordProperty("refused_colliding", refused_colliding);
}

}  // namespace
}  // namespace csp::test
