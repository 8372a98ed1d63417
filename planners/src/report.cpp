#include "csp/planners/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>

#include "csp/io/svg_plot.hpp"

namespace csp::planners {
namespace {

using Point = std::array<double, 2>;

// JSON has no infinity: a class without any pair, or a fraction of a zero limit, is null.
nlohmann::json finite_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

nlohmann::json joint_vector(const Vector7& v) {
  nlohmann::json out = nlohmann::json::array();
  for (int j = 0; j < kNumJoints; ++j) out.push_back(finite_or_null(v[j]));
  return out;
}

nlohmann::json to_json(const ClassClearance& c) {
  return {{"class", c.obstacle_class}, {"clearance", finite_or_null(c.clearance)},
          {"distance", finite_or_null(c.distance)}, {"t", c.t}, {"moving", c.moving}, {"other", c.other}};
}

// Andrew's monotone chain: the convex hull, counter-clockwise, closed (first point repeated).
std::vector<Point> convex_hull(std::vector<Point> p) {
  std::sort(p.begin(), p.end());
  if (p.size() < 3) return p;
  std::vector<Point> hull(2 * p.size());
  std::size_t k = 0;
  auto cross = [](const Point& o, const Point& a, const Point& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i > 0; --i) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i - 1]) <= 0) --k;
    hull[k++] = p[i - 1];
  }
  hull.resize(k);
  return hull;
}

// The outline of an obstacle seen along the axis not in {a, b} (side view: x, z; top view: x, y).
std::vector<Point> outline(const Shape& shape, int a, int b) {
  std::vector<Point> points;
  auto circle = [&](const Vector3& centre, double radius) {
    for (int i = 0; i < 32; ++i) {
      const double phi = 2.0 * std::numbers::pi * i / 32;
      points.push_back({centre[a] + radius * std::cos(phi), centre[b] + radius * std::sin(phi)});
    }
  };
  if (const auto* box = std::get_if<Box>(&shape)) {
    for (int corner = 0; corner < 8; ++corner) {
      const Vector3 local((corner & 1 ? 1 : -1) * box->half_size.x(), (corner & 2 ? 1 : -1) * box->half_size.y(),
                          (corner & 4 ? 1 : -1) * box->half_size.z());
      const Vector3 p = box->pose.rotation * local + box->pose.translation;
      points.push_back({p[a], p[b]});
    }
  } else if (const auto* capsule = std::get_if<Capsule>(&shape)) {
    circle(capsule->a, capsule->radius);
    circle(capsule->b, capsule->radius);
  } else if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    circle(sphere->center, sphere->radius);
  } else if (const auto* half = std::get_if<HalfSpace>(&shape)) {
    // Seen edge-on only when the normal lies in the view plane: its boundary is a line.
    const int dropped = 3 - a - b;
    if (std::abs(half->normal[dropped]) > 1e-9) return {};
    const Point along{-half->normal[b], half->normal[a]};
    for (double s : {-1.5, 1.5}) points.push_back({half->point[a] + s * along[0], half->point[b] + s * along[1]});
    return points;
  }
  std::vector<Point> hull = convex_hull(points);
  if (!hull.empty()) hull.push_back(hull.front());
  return hull;
}

std::string class_colour(const std::string& obstacle_class) {
  if (obstacle_class == "patient") return "#d62728";
  if (obstacle_class == "staff") return "#ff7f0e";
  return "#7f7f7f";
}

// At most about `count` of n indices, evenly spaced, the last included.
std::vector<std::size_t> thinned(std::size_t n, std::size_t count) {
  std::vector<std::size_t> out;
  const std::size_t step = std::max<std::size_t>(1, n / count);
  for (std::size_t k = 0; k < n; k += step) out.push_back(k);
  if (n > 0 && out.back() != n - 1) out.push_back(n - 1);
  return out;
}

PlotPanel tool_view(const TrajectoryCheck& check, const Scene& scene, int a, int b, const std::string& title) {
  const char* axis[] = {"x [m]", "y [m]", "z [m]"};
  PlotPanel panel{title, axis[a], axis[b], {}, {}};
  std::vector<std::string> labelled;
  for (const Obstacle& o : scene.obstacles) {
    const std::vector<Point> line = outline(o.shape, a, b);
    if (line.empty()) continue;
    const bool first = std::find(labelled.begin(), labelled.end(), o.obstacle_class) == labelled.end();
    if (first) labelled.push_back(o.obstacle_class);
    PlotSeries s{first ? o.obstacle_class : "", class_colour(o.obstacle_class), {}, {}};
    for (const Point& p : line) s.x.push_back(p[0]), s.y.push_back(p[1]);
    panel.series.push_back(s);
  }
  PlotSeries path{"tool (TCP) path", "#1f77b4", {}, {}};
  for (std::size_t k : thinned(check.tool_position.size(), 2000))
    path.x.push_back(check.tool_position[k][a]), path.y.push_back(check.tool_position[k][b]);
  panel.series.push_back(path);
  if (!check.tool_position.empty()) {
    const Vector3& start = check.tool_position.front();
    panel.series.push_back({"start", "#2ca02c", {start[a]}, {start[b]}, true});
  }
  return panel;
}

std::string joint_row(const char* name, const std::vector<JointUsage>& joints, double JointUsage::*member,
                      const char* pattern) {
  std::string row = format("| %s |", name);
  for (const JointUsage& u : joints) row.append(" ").append(format(pattern, u.*member)).append(" |");
  return row + "\n";
}

}  // namespace

bool EmulatorRun::passed() const {
  if (!reflex.empty()) return false;
  for (const ClassClearance& c : measured_clearance)
    if (c.clearance < 0.0) return false;
  return true;
}

nlohmann::json to_json(const TrajectoryCheck& check) {
  nlohmann::json failures = nlohmann::json::array();
  for (const CheckFailure& f : check.failures)
    failures.push_back({{"kind", f.kind}, {"joint", f.joint}, {"t", f.t}, {"row", f.row}, {"value", f.value},
                        {"limit", f.limit}, {"detail", f.detail}, {"message", describe(f)}});
  nlohmann::json joints = nlohmann::json::array();
  for (std::size_t j = 0; j < check.joints.size(); ++j) {
    const JointUsage& u = check.joints[j];
    joints.push_back({{"joint", j + 1},
                      {"position", u.position},
                      {"position_margin", u.position_margin},
                      {"velocity", finite_or_null(u.velocity)},
                      {"t_velocity", u.t_velocity},
                      {"acceleration", u.acceleration},
                      {"t_acceleration", u.t_acceleration},
                      {"jerk", u.jerk},
                      {"t_jerk", u.t_jerk},
                      {"torque", u.torque},
                      {"t_torque", u.t_torque},
                      {"torque_rate", u.torque_rate}});
  }
  nlohmann::json clearance = nlohmann::json::array();
  for (const ClassClearance& c : check.clearance) clearance.push_back(to_json(c));
  return {{"passed", check.passed},
          {"failures", failures},
          {"samples", check.samples},
          {"duration", check.duration},
          {"rate_hz", check.rate_hz},
          {"limit_usage", joints},
          {"power", {{"peak", check.peak_power}, {"t", check.t_peak_power}, {"limit", check.power_limit}}},
          {"tool_speed",
           {{"peak", check.peak_tool_speed}, {"t", check.t_peak_tool_speed}, {"limit", check.tool_speed_limit}}},
          {"clearance", clearance},
          {"uncertified_motions", check.uncertified_motions},
          {"min_clearance", {{"dense", finite_or_null(check.dense_min_clearance)},
                             {"certified", finite_or_null(check.certified_min_clearance)},
                             {"t_certified", check.t_certified_min}}}};
}

nlohmann::json to_json(const PlanReport& r) {
  nlohmann::json out = {{"passed", r.passed()}, {"title", r.title},     {"command", r.command_line},
                        {"scene", r.scene_name}, {"robot", r.robot_name}, {"problems", r.problems},
                        {"check", to_json(r.check)}};
  if (!r.plan.is_null()) out["plan"] = r.plan;
  if (r.verify) {
    const EmulatorRun& v = *r.verify;
    nlohmann::json clearance = nlohmann::json::array();
    for (const ClassClearance& c : v.measured_clearance) clearance.push_back(to_json(c));
    out["verify"] = {{"passed", v.passed()},
                     {"robot", v.robot},
                     {"reflex", v.reflex},
                     {"reflex_t", v.reflex.empty() ? nlohmann::json() : nlohmann::json(v.reflex_t)},
                     {"duration", v.duration},
                     {"tracking_rms", joint_vector(v.tracking_rms)},
                     {"tracking_max", joint_vector(v.tracking_max)},
                     {"peak_tau_J_fraction", joint_vector(v.peak_tau_J_fraction)},
                     {"measured_clearance", clearance}};
  }
  return out;
}

void write_report(const std::string& dir, const PlanReport& r, const Scene& scene) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir)) throw std::runtime_error("cannot create the report directory " + dir);
  const fs::path folder(dir);
  const TrajectoryCheck& c = r.check;

  // Limit usage per joint: one bar panel per limit.
  std::vector<PlotPanel> usage;
  const std::pair<const char*, double JointUsage::*> kinds[] = {
      {"position (of half the range)", &JointUsage::position}, {"velocity", &JointUsage::velocity},
      {"acceleration", &JointUsage::acceleration},             {"jerk", &JointUsage::jerk},
      {"torque", &JointUsage::torque},                         {"torque rate", &JointUsage::torque_rate}};
  for (const auto& [name, member] : kinds) {
    std::vector<double> fractions;
    for (const JointUsage& u : c.joints) fractions.push_back(u.*member);
    usage.push_back(joint_limit_panel(name, fractions));
  }
  PlotPanel power = joint_limit_panel("power (sum of the joints' positive powers)",
                                      {c.power_limit > 0.0 ? c.peak_power / c.power_limit : NAN});
  power.bar_labels = {"arm"};
  usage.push_back(power);
  write_text_file((folder / "limits.svg").string(), render_panels("Limit usage per joint", usage, 2));

  // Clearance over time: the smallest over all classes, the minimum of each stretch kept.
  PlotPanel clearance{"smallest clearance over all classes (distance - required)", "t [s]", "clearance [m]", {}, {}};
  PlotSeries line{"clearance", "#1f77b4", {}, {}};
  const std::size_t stretch = std::max<std::size_t>(1, c.t.size() / 2000);
  for (std::size_t k = 0; k < c.t.size(); k += stretch) {
    const auto end = c.min_clearance.begin() + static_cast<long>(std::min(c.t.size(), k + stretch));
    const auto lowest = std::min_element(c.min_clearance.begin() + static_cast<long>(k), end);
    line.x.push_back(c.t[static_cast<std::size_t>(lowest - c.min_clearance.begin())]);
    line.y.push_back(std::isfinite(*lowest) ? *lowest : 0.0);
  }
  clearance.series.push_back(line);
  if (!c.t.empty()) clearance.series.push_back({"required (0)", "#d62728", {c.t.front(), c.t.back()}, {0.0, 0.0}});
  write_text_file((folder / "clearance.svg").string(), render_panels("Clearance over time", {clearance}, 1));

  write_text_file((folder / "tool_path.svg").string(),
                  render_panels("Tool path in the scene (" + scene.name + ")",
                                {tool_view(c, scene, 0, 2, "side view (x, z)"), tool_view(c, scene, 0, 1, "top view (x, y)")},
                                2));
  if (!r.singular_values.empty()) {
    PlotPanel s{"singular values of the scaled regressor", "index", "log10(singular value)", {}, {}};
    PlotSeries points{"", "#9467bd", {}, {}, true};
    for (std::size_t i = 0; i < r.singular_values.size(); ++i)
      points.x.push_back(static_cast<double>(i + 1)), points.y.push_back(std::log10(std::max(r.singular_values[i], 1e-300)));
    s.series.push_back(points);
    write_text_file((folder / "singular_values.svg").string(), render_panels("Identifiability", {s}, 1));
  }

  write_text_file((folder / "report.json").string(), to_json(r).dump(2) + "\n");

  std::string md = "# " + r.title + "\n\n`" + r.command_line + "`\n\n";
  md += format("**%s**: scene `%s`, robot `%s`, %zu samples over %.3f s (%.0f Hz).\n\n",
               r.passed() ? "PASSED" : "FAILED", r.scene_name.c_str(), r.robot_name.c_str(), c.samples, c.duration,
               c.rate_hz);
  for (const std::string& p : r.problems) md += "- " + p + "\n";
  for (const CheckFailure& f : c.failures) md += "- " + describe(f) + "\n";
  if (!r.problems.empty() || !c.failures.empty()) md += "\n";
  md += "## Limit usage per joint (fraction of the limit)\n\n";
  md += "| | J1 | J2 | J3 | J4 | J5 | J6 | J7 |\n|---|---|---|---|---|---|---|---|\n";
  md += joint_row("position margin [rad]", c.joints, &JointUsage::position_margin, "%.3f");
  for (const auto& [name, member] : kinds) md += joint_row(name, c.joints, member, "%.3f");
  md += format("\nPeak power %.1f W (limit %.0f W) at t = %.3f s; peak tool speed %.3f m/s (limit %.3f m/s) at t = "
               "%.3f s.\n\n![limits](limits.svg)\n\n",
               c.peak_power, c.power_limit, c.t_peak_power, c.peak_tool_speed, c.tool_speed_limit, c.t_peak_tool_speed);
  md += "## Clearance per obstacle class (at every sample; every motion between samples certified)\n\n";
  md += "| class | clearance [m] | distance [m] | at t [s] | pair |\n|---|---|---|---|---|\n";
  for (const ClassClearance& k : c.clearance)
    md += std::isfinite(k.clearance)
              ? format("| %s | %.4f | %.4f | %.3f | %s vs %s |\n", k.obstacle_class.c_str(), k.clearance, k.distance,
                       k.t, k.moving.c_str(), k.other.c_str())
              : format("| %s | (no pair) | | | |\n", k.obstacle_class.c_str());
  md += format("\nMotions between samples not certified collision-free: %zu. Smallest clearance beyond the required: "
               "%.4f m at the samples (dense, %.0f Hz), %.4f m certified between them (t = %.3f s).\n\n",
               c.uncertified_motions, c.dense_min_clearance, c.rate_hz, c.certified_min_clearance, c.t_certified_min);
  md += "![clearance](clearance.svg)\n\n![tool path](tool_path.svg)\n\n";
  if (r.verify) {
    const EmulatorRun& v = *r.verify;
    md += format("## On the emulator (--verify, %s, %.3f s)\n\n", v.robot.c_str(), v.duration);
    if (v.reflex.empty()) md += "No reflex.\n\n";
    else {
      md += format("REFLEX at t = %.3f s:", v.reflex_t);
      for (const std::string& e : v.reflex) md += " `" + e + "`";
      md += "\n\n";
    }
    md += "| | J1 | J2 | J3 | J4 | J5 | J6 | J7 |\n|---|---|---|---|---|---|---|---|\n";
    auto row = [&](const char* name, const Vector7& value, double scale) {
      md += format("| %s |", name);
      for (int j = 0; j < kNumJoints; ++j) md += format(" %.3f |", scale * value[j]);
      md += "\n";
    };
    row("tracking RMS [mrad]", v.tracking_rms, 1e3);
    row("tracking max [mrad]", v.tracking_max, 1e3);
    row("peak tau_J / tau_max", v.peak_tau_J_fraction, 1.0);
    md += "\nClearance of the measured motion:\n\n| class | clearance [m] | at t [s] | pair |\n|---|---|---|---|\n";
    for (const ClassClearance& k : v.measured_clearance)
      if (std::isfinite(k.clearance))
        md += format("| %s | %.4f | %.3f | %s vs %s |\n", k.obstacle_class.c_str(), k.clearance, k.t, k.moving.c_str(),
                     k.other.c_str());
    md += "\n";
  }
  if (!r.singular_values.empty()) md += "## Identifiability\n\n![singular values](singular_values.svg)\n\n";
  if (!r.plan.is_null()) md += "## Plan\n\n```json\n" + r.plan.dump(2) + "\n```\n";
  write_text_file((folder / "report.md").string(), md);
}

}  // namespace csp::planners
