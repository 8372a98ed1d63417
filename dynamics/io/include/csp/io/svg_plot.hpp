// Figures as self-contained SVG files (no external libraries), for the workspace figures
// (`csp workspace`, csp/io/workspace_figures.hpp) and the gap report (`csp gap --report`):
// density heat maps, and panels of line, point or bar plots.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace csp {

// printf into a std::string: the figures' labels and numbers, the reports' text.
std::string format(const char* pattern, auto... values) {
  std::string out(static_cast<std::size_t>(std::max(0, std::snprintf(nullptr, 0, pattern, values...))), '\0');
  std::snprintf(out.data(), out.size() + 1, pattern, values...);
  return out;
}

// Writes `text` to `path`; throws std::runtime_error("cannot write <path>") on failure.
void write_text_file(const std::string& path, const std::string& text);

// The width [px] a line of text takes at `font_size` [px] in a sans-serif font (DejaVu Sans's
// widths, rounded up): what the layout uses to keep labels apart and titles inside the figure.
// Every <text> the renderer writes has its own x, y, font-size and text-anchor, so a reader of
// the SVG can estimate each one's box the same way.
double estimated_text_width(const std::string& text, double font_size);

// --- Density heat maps: log-scaled counts on a viridis colour scale, axes with ticks, title,
// colour bar, reference circles, markers and horizontal lines.

struct HeatMapCircle {
  double cx = 0.0, cy = 0.0, radius = 0.0;   // data units
  std::string label;                         // legend entry
  std::string colour = "#d62728";
  bool dashed = true;
};

struct HeatMapMarker {
  enum class Shape { kBase, kPoint };
  double x = 0.0, y = 0.0;
  std::string label;   // written next to the marker
  Shape shape = Shape::kPoint;
};

struct HeatMapLine {   // a horizontal reference line across the plot
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
  std::vector<HeatMapCircle> circles;
  std::vector<HeatMapMarker> markers;
  std::vector<HeatMapLine> lines;
};

// The figure shows the occupied cells, circles and markers (not the whole grid), with equal
// scales on both axes. Empty cells stay white. Throws std::invalid_argument when the counts do
// not match the grid.
std::string render_heat_map(const HeatMapFigure& figure);

// --- Panels sharing one style, in a grid of `columns`: lines, points or horizontal bars.
// The renderer lays out: long titles wrap (or shrink) to the figure's width, tick steps are
// 1, 2 or 5 times a power of ten with room for their labels, legends sit under the axes.

struct PlotSeries {
  std::string label, colour;
  std::vector<double> x, y;
  bool points = false;   // dots instead of a line
};

struct PlotPanel {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<std::string> bar_labels;   // non-empty: a bar chart, series[0].y the bar lengths
  // A bar chart of usage against a limit (> 0): the axis ends at the limit (100 %), a line marks
  // it, each bar's share of the limit is written after the axis, and bars beyond it end at the
  // axis in red, marked "over".
  double bar_limit = 0.0;
};

// The usage of one limit per joint (each value a fraction of its limit, 1 = the limit) as a limit
// chart "joint 1" .. "joint n": `csp plan`'s and `csp emulate`'s limits.svg.
PlotPanel joint_limit_panel(const std::string& title, const std::vector<double>& fractions);

std::string render_panels(const std::string& title, const std::vector<PlotPanel>& panels, int columns);

}  // namespace csp
