// csp workspace: Monte-Carlo reachable workspace (the seed paper's Fig. 3). Samples joint
// configurations uniformly within the joint limits, writes side and top density maps as SVG and
// prints the reach statistics next to Franka's published 855 mm maximum reach.
#include <algorithm>
#include <charconv>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/dynamics/workspace.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/io/workspace_figures.hpp"

namespace csp::cli {
namespace {

constexpr int kMaxGrid = 400;   // cells per axis; keeps the SVG files below a few MB

std::string millimetres(double metres) { return format("%.1f mm", 1000.0 * metres); }

// One CSV row of the point cloud, written with to_chars (6 decimals = micrometres) for speed.
void write_point_row(std::ostream& out, const Vector3& flange, const Vector3& end_effector) {
  char buffer[160];
  char* p = buffer;
  char* const end = buffer + sizeof buffer;
  for (const Vector3* v : {&flange, &end_effector})
    for (int k = 0; k < 3; ++k) {
      p = std::to_chars(p, end, (*v)[k], std::chars_format::fixed, 6).ptr;
      *p++ = (v == &end_effector && k == 2) ? '\n' : ',';
    }
  out.write(buffer, p - buffer);
}

// The 855 mm datasheet figure is for the arm's flange, so only the flange is compared with it.
void print_statistics(const char* name, const ReachStatistics& s, const Vector3& shoulder, bool compare) {
  const double excess = s.max_reach - kFrankaDatasheetReach;
  std::cout << format("  %-13s max reach from the shoulder %s", name, millimetres(s.max_reach).c_str())
            << (compare ? format(" (%+.1f mm, %+.2f%% vs Franka's 855 mm)\n", 1000.0 * excess,
                                 100.0 * excess / kFrankaDatasheetReach)
                        : std::string(" (beyond the flange, not comparable with 855 mm)\n"))
            << format("  %-13s   at q = [%.3f, %.3f, %.3f, %.3f, %.3f, %.3f, %.3f] rad\n", "",
                      s.q_at_max_reach[0], s.q_at_max_reach[1], s.q_at_max_reach[2], s.q_at_max_reach[3],
                      s.q_at_max_reach[4], s.q_at_max_reach[5], s.q_at_max_reach[6])
            << format("  %-13s max horizontal radius (from the joint-1 axis) %s\n", "", millimetres(s.max_radius).c_str())
            << format("  %-13s z range [%s, %s] (shoulder at z = %s)\n", "", millimetres(s.z_min).c_str(),
                      millimetres(s.z_max).c_str(), millimetres(shoulder.z()).c_str());
}

}  // namespace

int run_workspace(const WorkspaceArguments& args) {
  if (args.samples <= 0 || args.samples > kMaxWorkspaceSamples)
    throw UsageError("--samples: expected 1 to " + std::to_string(kMaxWorkspaceSamples) + " samples, got " +
                     std::to_string(args.samples) + " (the bound: a billion take about 7 minutes at 400 ns each, and --points 60 GB)");
  if (args.seed < 0) throw UsageError("--seed: expected a non-negative integer, got " + std::to_string(args.seed));
  if (args.grid < 10 || args.grid > kMaxGrid)
    throw UsageError("--grid: expected 10.." + std::to_string(kMaxGrid) + " cells per axis, got " +
                     std::to_string(args.grid));
  const Model model = args.model.build();

  // Check the outputs before sampling, so a bad path fails at once, before anything is printed.
  namespace fs = std::filesystem;
  Outputs()
      .directory("--out", args.out, {"workspace_side.svg", "workspace_top.svg"})
      .file("--points", args.points)
      .input("--robot", args.model.robot)
      .check();
  const fs::path dir(args.out);
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir))
    throw std::runtime_error("cannot create output directory " + dir.string() +
                             (error ? ": " + error.message() : ": not a directory"));
  const std::string side_path = (dir / "workspace_side.svg").string(), top_path = (dir / "workspace_top.svg").string();
  std::ofstream points;
  if (!args.points.empty()) {
    points.open(args.points, std::ios::binary);
    if (!points) throw std::runtime_error(args.points + ": cannot write the points (" + std::strerror(errno) + ")");
    std::cerr << format("csp workspace: writing %lld points to %s (about %.0f MB)\n", args.samples,
                        args.points.c_str(), 60e-6 * static_cast<double>(args.samples));
    points << "flange_x,flange_y,flange_z,ee_x,ee_y,ee_z\n";
  }

  WorkspaceOptions options;
  options.samples = args.samples;
  options.seed = static_cast<std::uint64_t>(args.seed);
  options.grid = args.grid;
  options.frame = Frame::kEndEffector;   // = the flange when --ee none
  ProgressMeter progress("csp workspace", args.progress);
  options.progress = progress.callback();
  WorkspaceCallback on_point;
  if (points.is_open())
    on_point = [&](const WorkspacePoint& p) {
      write_point_row(points, p.flange, p.end_effector);
      // A disk that fills ends the sampling at once, not after the last of a billion samples.
      if (!points) throw std::runtime_error(args.points + ": writing the points failed (" + std::strerror(errno) + ")");
    };

  const auto start = std::chrono::steady_clock::now();
  const WorkspaceResult result = sample_workspace(model, options, on_point);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (points.is_open()) {
    points.close();
    if (!points) throw std::runtime_error(args.points + ": writing the points failed (" + std::strerror(errno) + ")");
  }

  // Figures of the end-effector positions (the flange itself when there is no end effector).
  const bool flange_only = model.parameters().F_T_EE.translation.isZero() && model.parameters().F_T_EE.rotation.isIdentity();
  const std::string robot = fs::path(args.model.robot).stem().string();
  const WorkspaceFigures figures = workspace_figures(result, options, robot, flange_only ? "" : args.model.end_effector);
  write_text_file(side_path, render_heat_map(figures.side));
  write_text_file(top_path, render_heat_map(figures.top));
  progress.finish(format("%lld samples, figures in %s", args.samples, args.out.c_str()));

  std::cout << format("csp workspace: %s, end effector %s, %lld samples, seed %lld\n", robot.c_str(),
                      args.model.end_effector.c_str(), args.samples, args.seed)
            << "sampling: each q_i uniform in [q_min_i, q_max_i] of the joint limits, independent, mt19937_64;\n"
            << "          positions by forward kinematics (MDH chain, flange = O_T_F, end effector = O_T_EE)\n"
            << format("reach = Euclidean distance from the shoulder, the joint-2 origin (%.3f, %.3f, %.3f) m,\n",
                      result.shoulder.x(), result.shoulder.y(), result.shoulder.z())
            << "        compared with Franka's published maximum reach of 855 mm; a sampled maximum\n"
            << "        approaches the true maximum from below as the number of samples grows\n";
  print_statistics("flange", result.flange, result.shoulder, true);
  if (!flange_only) print_statistics("end effector", result.end_effector, result.shoulder, false);
  std::cout << format("density grids: %d x %d cells of %.1f mm, %llu samples outside\n", result.side.nx, result.side.ny,
                      1000 * result.side.cell_width(),
                      static_cast<unsigned long long>(result.side.outside + result.top.outside))
            << "figures: " << side_path << ", " << top_path << '\n'
            << format("time: %.3f s sampling (%.0f ns per sample)%s\n", seconds,
                      1e9 * seconds / static_cast<double>(args.samples),
                      args.points.empty() ? "" : ", including the CSV");
  return 0;
}

Command add_workspace_command(CLI::App& app) {
  auto args = std::make_shared<WorkspaceArguments>();
  CLI::App* command = app.add_subcommand(
      "workspace", "Sample the reachable workspace (uniform joint configurations), write side/top density SVGs, print reach statistics");
  args->model.add_to(*command);
  command->add_option("--samples", args->samples, "Number of joint configurations, uniform within the joint limits")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Seed of the mt19937_64 generator")
      ->capture_default_str();
  command->add_option("--out", args->out, "Output directory for workspace_side.svg and workspace_top.svg")
      ->capture_default_str();
  command->add_option("--points", args->points,
                      "Also write the point cloud as CSV: flange x,y,z and end-effector x,y,z per sample [m] "
                      "(large: about 60 bytes per sample)");
  command->add_option("--grid", args->grid, "Histogram cells per axis (10.." + std::to_string(kMaxGrid) + ")")
      ->capture_default_str();
  add_progress_flag(*command, args->progress);

  return [args] { return run_workspace(*args); };
}

}  // namespace csp::cli
