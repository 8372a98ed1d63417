// Density heat maps as self-contained SVG files (no external libraries): log-scaled counts on a
// viridis colour scale, axes with ticks, title, colour bar, reference circles and markers.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace csp::cli {

struct FigureCircle {
  double cx = 0.0, cy = 0.0, radius = 0.0;   // data units
  std::string label;                         // legend entry
  std::string colour = "#d62728";
  bool dashed = true;
};

struct FigureMarker {
  enum class Shape { kBase, kPoint };
  double x = 0.0, y = 0.0;
  std::string label;   // written next to the marker
  Shape shape = Shape::kPoint;
};

struct FigureLine {   // a horizontal reference line across the plot
  double y = 0.0;
  std::string label;
};

struct HeatMapFigure {
  std::string title, subtitle;
  std::string x_label, y_label, colour_label;
  // The grid: nx x ny cells over [x_min, x_max) x [y_min, y_max); counts[iy * nx + ix], iy = 0 at y_min.
  double x_min = 0.0, x_max = 1.0, y_min = 0.0, y_max = 1.0;
  int nx = 0, ny = 0;
  std::vector<std::uint64_t> counts;
  std::vector<FigureCircle> circles;
  std::vector<FigureMarker> markers;
  std::vector<FigureLine> lines;
};

// The figure shows the occupied cells, circles and markers (not the whole grid), with equal
// scales on both axes. Empty cells stay white.
std::string render_svg(const HeatMapFigure& figure);

// Throws std::runtime_error("cannot write <path>") on failure.
void write_svg(const std::string& path, const HeatMapFigure& figure);

}  // namespace csp::cli
