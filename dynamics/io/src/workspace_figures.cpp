#include "csp/io/workspace_figures.hpp"

namespace csp {
namespace {

std::string millimetres(double metres) { return format("%.1f mm", 1000.0 * metres); }

// `measured` is the sampled radius drawn for comparison: max reach (side) or max horizontal radius (top).
HeatMapFigure density_map(const Histogram2D& h, const std::string& measured_label, double measured,
                          const std::string& subtitle) {
  HeatMapFigure f;
  f.x_min = h.x_min, f.x_max = h.x_max, f.y_min = h.y_min, f.y_max = h.y_max;
  f.nx = h.nx, f.ny = h.ny;
  f.counts = h.counts;
  f.subtitle = subtitle;
  f.colour_label =
      format("samples per %.0f mm × %.0f mm cell (log scale)", 1000 * h.cell_width(), 1000 * h.cell_height());
  // Drawn in this order: the dashed datasheet circle stays visible on top of the (nearly equal) sampled one.
  f.circles.push_back({0, 0, measured, measured_label + " " + millimetres(measured), "#111111", false});
  f.circles.push_back({0, 0, kFrankaDatasheetReach,
                       "Franka datasheet reach " + format("%.0f mm", 1000 * kFrankaDatasheetReach), "#d62728", true});
  return f;
}

}  // namespace

WorkspaceFigures workspace_figures(const WorkspaceResult& result, const WorkspaceOptions& options,
                                   const std::string& robot, const std::string& end_effector) {
  const bool flange_only = end_effector.empty();
  const std::string what = flange_only ? "flange" : "end effector (" + end_effector + ")";
  const std::string subtitle = format("%lld uniform joint configurations, seed %llu; circles centred on the shoulder "
                                      "(joint-2 origin)",
                                      static_cast<long long>(options.samples),
                                      static_cast<unsigned long long>(options.seed));
  const ReachStatistics& shown = flange_only ? result.flange : result.end_effector;
  const Vector3& shoulder = result.shoulder;

  WorkspaceFigures figures;
  HeatMapFigure& side = figures.side;
  side = density_map(result.side, "sampled max reach from the shoulder", shown.max_reach, subtitle);
  side.title = robot + " workspace, side view: " + what + " position";
  side.x_label = "signed horizontal radius sign(x)·√(x² + y²) [m]";
  side.y_label = "z [m]";
  for (auto& c : side.circles) c.cy = shoulder.z();
  side.markers = {{0.0, 0.0, "base", HeatMapMarker::Shape::kBase},
                  {0.0, shoulder.z(), "shoulder (joint 2)", HeatMapMarker::Shape::kPoint}};
  side.lines = {{0.0, "base plane z = 0"}};

  HeatMapFigure& top = figures.top;
  top = density_map(result.top, "sampled max horizontal radius", shown.max_radius, subtitle);
  top.title = robot + " workspace, top view: " + what + " position";
  top.x_label = "x [m]";
  top.y_label = "y [m]";
  for (auto& c : top.circles) c.cx = shoulder.x(), c.cy = shoulder.y();
  top.markers = {{0.0, 0.0, "base / shoulder", HeatMapMarker::Shape::kBase}};
  return figures;
}

}  // namespace csp
