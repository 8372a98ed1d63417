#include "csp/io/svg_plot.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <cctype>

namespace csp {
namespace {

std::string number(double v, int decimals) { return format("%.*f", decimals, v); }

std::string escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Axis ticks: the smallest 1, 2 or 5 times a power of ten that is at least `raw`.
double nice_step(double raw) {
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw * (1 - 1e-9)) return m * power;
  return 10.0 * power;
}

// --- Heat maps -----------------------------------------------------------------------------------

constexpr int kLevels = 64;            // colour levels; few enough that runs of equal cells merge
constexpr double kMaxPlotSize = 560;   // px, longer side of the plot area
constexpr double kMapLeft = 80;
constexpr const char* kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";
const std::string kHalo = " stroke='white' stroke-width='3' paint-order='stroke'";   // legible over the map

// Viridis (matplotlib) sampled at 0, 1/8, ..., 1 and interpolated linearly.
std::string colour(double t) {
  static constexpr std::array<std::array<int, 3>, 9> kViridis{{{68, 1, 84}, {71, 45, 123}, {59, 82, 139},
                                                               {44, 114, 142}, {33, 145, 140}, {40, 174, 128},
                                                               {94, 201, 98}, {173, 220, 48}, {253, 231, 37}}};
  t = std::clamp(t, 0.0, 1.0) * 8.0;
  const int i = std::min(static_cast<int>(t), 7);
  const double f = t - i;
  int rgb[3];
  for (int k = 0; k < 3; ++k) rgb[k] = static_cast<int>(std::lround(kViridis[i][k] + f * (kViridis[i + 1][k] - kViridis[i][k])));
  return format("#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
}

std::string level_colour(int level) { return colour(static_cast<double>(level) / (kLevels - 1)); }

int decimals_for(double step) { return std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9))); }

struct Range {
  double min = HUGE_VAL, max = -HUGE_VAL;
  void include(double v) {
    min = std::min(min, v);
    max = std::max(max, v);
  }
};

// --- Text ----------------------------------------------------------------------------------------

constexpr double kPanelWidth = 460, kPlotHeight = 160;
constexpr double kTickFont = 10, kLabelFont = 11, kPanelTitleFont = 13, kFigureTitleFont = 15;
constexpr const char* kOverColour = "#d62728";

// One <text>: every one carries its own position, size and anchor (see estimated_text_width).
std::string text_element(double x, double y, double size, const char* anchor, const std::string& text,
                         const std::string& extra = "") {
  return format("<text x='%.1f' y='%.1f' font-size='%.1f' text-anchor='%s'%s>%s</text>\n", x, y, size, anchor,
                extra.c_str(), escape(text).c_str());
}

// Text in lines no wider than `width`: words wrap at spaces; when a single word is still too wide,
// the font shrinks (down to 7 px).
struct FittedText {
  std::vector<std::string> lines;
  double size = 0.0;
};

FittedText fit_text(const std::string& text, double size, double width) {
  for (;; size *= 0.9) {
    FittedText fitted{{}, size};
    std::istringstream words(text);
    bool fits = true;
    for (std::string word; words >> word;) {
      const std::string longer = fitted.lines.empty() ? word : fitted.lines.back() + ' ' + word;
      if (!fitted.lines.empty() && estimated_text_width(longer, size) <= width) fitted.lines.back() = longer;
      else fitted.lines.push_back(word);
      fits = fits && estimated_text_width(fitted.lines.back(), size) <= width;
    }
    if (fits || size < 7.5) return fitted;
  }
}

double line_height(double size) { return 1.25 * size; }

// The fitted text's lines from baseline `y`; returns the height taken.
double write_lines(std::ostream& svg, const FittedText& text, double x, double y, const char* anchor,
                   const std::string& extra = "") {
  for (std::size_t i = 0; i < text.lines.size(); ++i)
    svg << text_element(x, y + static_cast<double>(i) * line_height(text.size), text.size, anchor, text.lines[i], extra);
  return static_cast<double>(text.lines.size()) * line_height(text.size);
}

}  // namespace

std::string render_heat_map(const HeatMapFigure& f) {
  if (f.nx < 1 || f.ny < 1 || f.counts.size() != static_cast<std::size_t>(f.nx) * f.ny)
    throw std::invalid_argument("render_heat_map: counts do not match the grid");
  const double cw = (f.x_max - f.x_min) / f.nx, ch = (f.y_max - f.y_min) / f.ny;

  // What to show: occupied cells, circles and markers.
  Range xr, yr;
  std::uint64_t max_count = 0;
  for (int iy = 0; iy < f.ny; ++iy)
    for (int ix = 0; ix < f.nx; ++ix) {
      const std::uint64_t c = f.counts[static_cast<std::size_t>(iy) * f.nx + ix];
      if (c == 0) continue;
      max_count = std::max(max_count, c);
      xr.include(f.x_min + ix * cw), xr.include(f.x_min + (ix + 1) * cw);
      yr.include(f.y_min + iy * ch), yr.include(f.y_min + (iy + 1) * ch);
    }
  for (const auto& c : f.circles) {
    xr.include(c.cx - c.radius), xr.include(c.cx + c.radius);
    yr.include(c.cy - c.radius), yr.include(c.cy + c.radius);
  }
  for (const auto& m : f.markers) xr.include(m.x), yr.include(m.y);
  if (xr.min > xr.max) xr = {f.x_min, f.x_max}, yr = {f.y_min, f.y_max};
  const double step = nice_step(std::max(xr.max - xr.min, yr.max - yr.min) / 12.0);
  const double pad = 0.1 * step;   // keep data off the frame, then snap outward to half ticks
  const double x0 = std::floor((xr.min - pad) / (step / 2)) * (step / 2), x1 = std::ceil((xr.max + pad) / (step / 2)) * (step / 2);
  const double y0 = std::floor((yr.min - pad) / (step / 2)) * (step / 2), y1 = std::ceil((yr.max + pad) / (step / 2)) * (step / 2);

  // The title and subtitle wrap to the figure's width; the map starts below them.
  const double min_width = 800.0;
  const FittedText title = fit_text(f.title, 17, min_width - kMapLeft - 10);
  const FittedText subtitle = fit_text(f.subtitle, 12, min_width - kMapLeft - 10);
  const double map_top = 12 + line_height(title.size) * static_cast<double>(title.lines.size()) +
                         line_height(subtitle.size) * static_cast<double>(subtitle.lines.size()) + 10;
  const double scale = kMaxPlotSize / std::max(x1 - x0, y1 - y0);   // px per data unit, equal on both axes
  const double width = (x1 - x0) * scale, height = (y1 - y0) * scale;
  auto px = [&](double x) { return kMapLeft + (x - x0) * scale; };
  auto py = [&](double y) { return map_top + (y1 - y) * scale; };
  const double bar_x = kMapLeft + width + 26, bar_w = 16;
  const double legend_y = map_top + height + 70;
  // The colour bar's label after its widest tick label (the largest count, or 1000).
  const double colour_label_x =
      bar_x + bar_w + 7 + std::max(estimated_text_width(std::to_string(max_count), 12), estimated_text_width("1000", 12)) + 14;
  const double total_w = std::max(colour_label_x + 10, min_width), total_h = legend_y + (f.circles.empty() ? 0 : 22);
  const int decimals = decimals_for(step);

  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << number(total_w, 0) << "\" height=\"" << number(total_h, 0)
    << "\" viewBox=\"0 0 " << number(total_w, 0) << ' ' << number(total_h, 0) << "\" font-family=\"" << kFont
    << "\" font-size=\"13\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  const double title_height = write_lines(s, title, kMapLeft, 6 + title.size, "start", " font-weight='bold'");
  write_lines(s, subtitle, kMapLeft, 6 + title_height + subtitle.size, "start", " fill='#444'");

  // Heat map: one path per colour level, each row's runs of equal level merged into one rectangle.
  // The group maps cell indices to pixels (y flipped), so path coordinates are small integers.
  std::vector<std::string> paths(kLevels);
  const double log_max = std::log(static_cast<double>(std::max<std::uint64_t>(max_count, 2)));
  auto level_of = [&](std::uint64_t c) {
    if (c == 0) return -1;
    return std::min(kLevels - 1, static_cast<int>(std::log(static_cast<double>(c)) / log_max * kLevels));
  };
  for (int iy = 0; iy < f.ny; ++iy) {
    for (int ix = 0; ix < f.nx;) {
      const int level = level_of(f.counts[static_cast<std::size_t>(iy) * f.nx + ix]);
      int end = ix + 1;
      while (end < f.nx && level_of(f.counts[static_cast<std::size_t>(iy) * f.nx + end]) == level) ++end;
      if (level >= 0) {
        char run[64];
        std::snprintf(run, sizeof run, "M%d %dh%dv1h-%dz", ix, iy, end - ix, end - ix);
        paths[level] += run;
      }
      ix = end;
    }
  }
  s << "<g transform=\"matrix(" << number(cw * scale, 5) << " 0 0 " << number(-ch * scale, 5) << ' '
    << number(px(f.x_min), 3) << ' ' << number(py(f.y_min), 3) << ")\" shape-rendering=\"crispEdges\">\n";
  for (int level = 0; level < kLevels; ++level)
    if (!paths[level].empty()) s << "<path fill=\"" << level_colour(level) << "\" d=\"" << paths[level] << "\"/>\n";
  s << "</g>\n";

  // Reference lines, circles, markers.
  for (const auto& line : f.lines) {
    if (line.y < y0 || line.y > y1) continue;
    s << "<line x1=\"" << number(px(x0), 1) << "\" y1=\"" << number(py(line.y), 1) << "\" x2=\"" << number(px(x1), 1)
      << "\" y2=\"" << number(py(line.y), 1) << "\" stroke=\"#666\" stroke-width=\"1\" stroke-dasharray=\"2 3\"/>\n"
      << text_element(px(x0) + 6, py(line.y) - 5, 11, "start", line.label, kHalo + " fill='#444'");
  }
  for (const auto& c : f.circles)
    s << "<circle cx=\"" << number(px(c.cx), 2) << "\" cy=\"" << number(py(c.cy), 2) << "\" r=\""
      << number(c.radius * scale, 2) << "\" fill=\"none\" stroke=\"" << c.colour << "\" stroke-width=\"1.8\""
      << (c.dashed ? " stroke-dasharray=\"8 5\"" : "") << "/>\n";
  for (const auto& m : f.markers) {
    const double mx = px(m.x), my = py(m.y);
    if (m.shape == HeatMapMarker::Shape::kBase)
      s << "<rect x=\"" << number(mx - 7, 1) << "\" y=\"" << number(my - 7, 1)
        << "\" width=\"14\" height=\"14\" fill=\"#333\" stroke=\"white\" stroke-width=\"1.5\"/>\n";
    else
      s << "<circle cx=\"" << number(mx, 1) << "\" cy=\"" << number(my, 1)
        << "\" r=\"4\" fill=\"white\" stroke=\"black\" stroke-width=\"1.5\"/>\n";
    s << text_element(mx + 10, my + 4, 12, "start", m.label, kHalo);
  }

  // Frame, ticks and labels.
  s << "<rect x=\"" << number(kMapLeft, 1) << "\" y=\"" << number(map_top, 1) << "\" width=\"" << number(width, 1)
    << "\" height=\"" << number(height, 1) << "\" fill=\"none\" stroke=\"black\"/>\n";
  // Every tick labelled, or every other one when the labels would touch.
  const int label_every = estimated_text_width(number(-std::max(std::abs(x0), std::abs(x1)), decimals), 13) + 6 > step * scale ? 2 : 1;
  for (double v = std::ceil(x0 / step - 1e-9) * step; v <= x1 + 1e-9 * step; v += step) {
    const double x = px(v), value = std::abs(v) < 1e-9 * step ? 0.0 : v;
    s << "<line x1=\"" << number(x, 1) << "\" y1=\"" << number(map_top + height, 1) << "\" x2=\"" << number(x, 1)
      << "\" y2=\"" << number(map_top + height + 5, 1) << "\" stroke=\"black\"/>";
    if (std::lround(v / step) % label_every == 0)
      s << text_element(x, map_top + height + 19, 13, "middle", number(value, decimals));
  }
  for (double v = std::ceil(y0 / step - 1e-9) * step; v <= y1 + 1e-9 * step; v += step) {
    const double y = py(v), value = std::abs(v) < 1e-9 * step ? 0.0 : v;
    s << "<line x1=\"" << number(kMapLeft - 5, 1) << "\" y1=\"" << number(y, 1) << "\" x2=\"" << number(kMapLeft, 1)
      << "\" y2=\"" << number(y, 1) << "\" stroke=\"black\"/>"
      << text_element(kMapLeft - 8, y + 4, 13, "end", number(value, decimals));
  }
  s << text_element(kMapLeft + width / 2, map_top + height + 42, 13, "middle", f.x_label)
    << text_element(kMapLeft - 52, map_top + height / 2, 13, "middle", f.y_label,
                    format(" transform='rotate(-90 %.1f %.1f)'", kMapLeft - 52, map_top + height / 2));

  // Colour bar: the same levels as the map, log10 ticks at powers of ten.
  const double level_h = height / kLevels;
  s << "<g shape-rendering=\"crispEdges\">";
  for (int level = 0; level < kLevels; ++level)
    s << "<rect x=\"" << number(bar_x, 1) << "\" y=\"" << number(map_top + height - (level + 1) * level_h, 2)
      << "\" width=\"" << number(bar_w, 0) << "\" height=\"" << number(level_h + 0.3, 2) << "\" fill=\""
      << level_colour(level) << "\"/>";
  s << "</g>\n<rect x=\"" << number(bar_x, 1) << "\" y=\"" << number(map_top, 1) << "\" width=\"" << number(bar_w, 0)
    << "\" height=\"" << number(height, 1) << "\" fill=\"none\" stroke=\"black\"/>\n";
  auto bar_tick = [&](double count, const std::string& label) {
    const double t = max_count > 1 ? std::log(count) / std::log(static_cast<double>(max_count)) : 1.0;
    const double y = map_top + height * (1 - t);
    s << "<line x1=\"" << number(bar_x + bar_w, 1) << "\" y1=\"" << number(y, 1) << "\" x2=\""
      << number(bar_x + bar_w + 4, 1) << "\" y2=\"" << number(y, 1) << "\" stroke=\"black\"/>"
      << text_element(bar_x + bar_w + 7, y + 4, 12, "start", label);
  };
  double last_power = 1;
  for (double c = 1; c <= static_cast<double>(std::max<std::uint64_t>(max_count, 1)); c *= 10) {
    bar_tick(c, c < 1e4 ? number(c, 0) : "1e" + number(std::log10(c), 0));
    last_power = c;
  }
  if (max_count > 1 && std::log(static_cast<double>(max_count) / last_power) > 0.12 * std::log(static_cast<double>(max_count)))
    bar_tick(static_cast<double>(max_count), std::to_string(max_count));
  const double colour_label_y = map_top + height / 2;
  s << text_element(colour_label_x, colour_label_y, 12, "middle", f.colour_label,
                    format(" transform='rotate(-90 %.1f %.1f)'", colour_label_x, colour_label_y));

  // Legend of the circles, below the x label.
  double lx = kMapLeft;
  for (const auto& c : f.circles) {
    s << "<line x1=\"" << number(lx, 1) << "\" y1=\"" << number(legend_y - 4, 1) << "\" x2=\"" << number(lx + 30, 1)
      << "\" y2=\"" << number(legend_y - 4, 1) << "\" stroke=\"" << c.colour << "\" stroke-width=\"1.8\""
      << (c.dashed ? " stroke-dasharray=\"8 5\"" : "") << "/>"
      << text_element(lx + 36, legend_y, 12, "start", c.label);
    lx += 48 + estimated_text_width(c.label, 12);
  }
  s << "</svg>\n";
  return s.str();
}

namespace {

// --- Panels --------------------------------------------------------------------------------------

// Axis ticks at a nice step: the first of 1, 2, 5 x 10^k (from at most six ticks on) whose labels
// have room along the axis: their estimated width on a horizontal axis, their height on a vertical one.
struct Ticks {
  std::vector<double> values;
  std::vector<std::string> labels;
};

Ticks axis_ticks(double lo, double hi, double length_px, const std::string& suffix, bool along_width) {
  for (double step = nice_step((hi - lo) / 6.0);; step = nice_step(step * 1.5)) {
    Ticks ticks;
    const int decimals = decimals_for(step);
    double extent = 0.0;
    for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0) {
      const double v = k == 0.0 ? 0.0 : k * step;
      ticks.values.push_back(v);
      ticks.labels.push_back(number(v, decimals) + suffix);
      extent = std::max(extent, along_width ? estimated_text_width(ticks.labels.back(), kTickFont) : kTickFont);
    }
    if (ticks.values.size() <= 2 || step / (hi - lo) * length_px >= extent + 6) return ticks;
  }
}

bool finite_point(const PlotSeries& s, std::size_t i) { return std::isfinite(s.x[i]) && std::isfinite(s.y[i]); }

// A line's points in pixels. A time series (x never decreasing) denser than the pixels keeps, per
// pixel column, its lowest and highest point in their order: the same picture, peaks included, in
// a file of a few thousand points however long the run.
std::vector<std::pair<double, double>> polyline_points(const PlotSeries& s, const auto& px, const auto& py) {
  std::vector<std::pair<double, double>> all;
  bool time_series = true;
  for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
    if (finite_point(s, i)) {
      time_series = time_series && (all.empty() || px(s.x[i]) >= all.back().first);
      all.emplace_back(px(s.x[i]), py(s.y[i]));
    }
  if (!time_series || all.size() < 2 || static_cast<double>(all.size()) <= 2 * (all.back().first - all.front().first + 1))
    return all;
  std::vector<std::pair<double, double>> kept;
  for (std::size_t begin = 0; begin < all.size();) {
    std::size_t end = begin, low = begin, high = begin;
    for (; end < all.size() && std::floor(all[end].first) == std::floor(all[begin].first); ++end) {
      if (all[end].second > all[low].second) low = end;   // pixels: y grows downwards
      if (all[end].second < all[high].second) high = end;
    }
    kept.push_back(all[std::min(low, high)]);
    if (low != high) kept.push_back(all[std::max(low, high)]);
    begin = end;
  }
  return kept;
}

struct Bounds {
  double x_min, x_max, y_min, y_max;
};

Bounds data_bounds(const PlotPanel& panel) {
  Range x, y;
  if (!panel.bar_labels.empty()) {
    x.include(0.0);
    for (const double v : panel.series[0].y)
      if (std::isfinite(v)) x.include(v);
    if (panel.bar_limit > 0.0) x = {0.0, panel.bar_limit};
    y = {0.0, static_cast<double>(panel.bar_labels.size())};
  } else {
    for (const PlotSeries& s : panel.series)
      for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
        if (finite_point(s, i)) x.include(s.x[i]), y.include(s.y[i]);
  }
  if (x.min > x.max) x = {0.0, 1.0};
  if (y.min > y.max) y = {0.0, 1.0};
  if (!(x.max > x.min)) x.max = x.min + 1.0;
  if (!(y.max > y.min)) y.max = y.min + 1.0;
  if (panel.bar_labels.empty()) {
    // Lines keep off the frame (a limit drawn as a line stays visible), and an axis that ends just
    // short of a tick (a time axis from the first 1 ms cycle) reaches it.
    const double pad = 0.04 * (y.max - y.min);
    y = {y.min - pad, y.max + pad};
    const double step = nice_step((x.max - x.min) / 5.0), near = 0.03 * (x.max - x.min);
    if (x.min - std::floor(x.min / step) * step < near) x.min = std::floor(x.min / step) * step;
    if (std::ceil(x.max / step) * step - x.max < near) x.max = std::ceil(x.max / step) * step;
  }
  return {x.min, x.max, y.min, y.max};
}

// The legend's entries in rows under the axes, wrapped at the panel's width; returns the height taken.
double write_legend(std::ostream& svg, const std::vector<PlotSeries>& entries, double left, double right, double top) {
  double x = left, y = top + kTickFont;
  for (const PlotSeries& s : entries) {
    const double width = 22 + estimated_text_width(s.label, kTickFont);
    if (x > left && x + width > right) x = left, y += line_height(kTickFont) + 2;
    if (s.points)
      svg << format("<circle cx='%.1f' cy='%.1f' r='2.5' fill='%s'/>\n", x + 8, y - 3.5, s.colour.c_str());
    else
      svg << format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' stroke-width='1.5'%s/>\n", x,
                    y - 3.5, x + 16, y - 3.5, s.colour.c_str(),
                    s.colour == kOverColour && s.label.starts_with("limit") ? " stroke-dasharray='4 2'" : "");
    svg << text_element(x + 20, y, kTickFont, "start", s.label);
    x += width + 12;
  }
  return entries.empty() ? 0.0 : y - top + 4;
}

// One panel with its top-left corner at (x0, y0); returns its height.
double render_panel(std::ostream& svg, const PlotPanel& panel, double x0, double y0) {
  const bool bars = !panel.bar_labels.empty();
  const bool limit = bars && panel.bar_limit > 0.0;
  const Bounds b = data_bounds(panel);
  const std::size_t n_bars = panel.bar_labels.size();
  // Bars about 22 px apart, closer when many (down to 15 px, what a label needs), one alone not a block.
  const double plot_height =
      bars ? std::max(15.0 * static_cast<double>(n_bars), std::min(kPlotHeight, 22.0 * static_cast<double>(n_bars)) + 8)
           : kPlotHeight;

  const FittedText title = fit_text(panel.title, kPanelTitleFont, kPanelWidth - 20);
  const double plot_top = y0 + 8 + write_lines(svg, title, x0 + kPanelWidth / 2, y0 + 6 + kPanelTitleFont, "middle") + 6;
  const double plot_bottom = plot_top + plot_height;

  // The value axis is horizontal (x) for every kind; a limit chart's in per cent of the limit.
  const double scale = limit ? 100.0 / panel.bar_limit : 1.0;
  const Ticks y_ticks = bars ? Ticks{} : axis_ticks(b.y_min, b.y_max, plot_height, "", false);
  const FittedText y_label = fit_text(panel.y_label, kLabelFont, plot_height);
  double left = 10 + (panel.y_label.empty() ? 0.0 : line_height(y_label.size) * static_cast<double>(y_label.lines.size()));
  double widest = 0.0;
  for (const std::string& label : bars ? panel.bar_labels : y_ticks.labels)
    widest = std::max(widest, estimated_text_width(label, kTickFont));
  left += widest + 8;
  std::vector<std::string> values;   // a limit chart's column after the axis
  double right = 20;   // half the last tick label
  for (std::size_t i = 0; limit && i < n_bars; ++i) {
    const double v = panel.series[0].y[i];
    values.push_back(!std::isfinite(v) ? "n/a" : format("%.0f %%%s", 100.0 * v / panel.bar_limit, v > panel.bar_limit ? " over" : ""));
    right = std::max(right, estimated_text_width(values.back(), kTickFont) + 12);
  }
  // The last x tick label is centred on the axis' end: the right margin holds its half.
  Ticks x_ticks = axis_ticks(b.x_min * scale, b.x_max * scale, kPanelWidth - left - right, limit ? " %" : "", true);
  const double half_label = estimated_text_width(x_ticks.labels.back(), kTickFont) / 2 + 2;
  if (half_label > right) {
    right = half_label;
    x_ticks = axis_ticks(b.x_min * scale, b.x_max * scale, kPanelWidth - left - right, limit ? " %" : "", true);
  }
  const double plot_left = x0 + left, plot_width = kPanelWidth - left - right;

  auto px = [&](double x) { return plot_left + (x - b.x_min) / (b.x_max - b.x_min) * plot_width; };
  auto py = [&](double y) { return plot_bottom - (y - b.y_min) / (b.y_max - b.y_min) * plot_height; };

  svg << format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' stroke='#444'/>\n", plot_left, plot_top,
                plot_width, plot_height);
  for (std::size_t i = 0; i < x_ticks.values.size(); ++i) {
    const double x = px(x_ticks.values[i] / scale);
    svg << format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#444'/>\n", x, plot_bottom, x, plot_bottom + 4)
        << text_element(x, plot_bottom + 6 + kTickFont, kTickFont, "middle", x_ticks.labels[i]);
  }
  for (std::size_t i = 0; i < y_ticks.values.size(); ++i) {
    const double y = py(y_ticks.values[i]);
    svg << format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#444'/>\n", plot_left - 4, y, plot_left, y)
        << text_element(plot_left - 6, y + 0.35 * kTickFont, kTickFont, "end", y_ticks.labels[i]);
  }
  double below = plot_bottom + 8 + line_height(kTickFont);
  below += write_lines(svg, fit_text(panel.x_label, kLabelFont, plot_width), plot_left + plot_width / 2,
                       below + kLabelFont, "middle");
  for (std::size_t i = 0; i < y_label.lines.size(); ++i) {   // rotated: the first line outermost
    const double x = x0 + 4 + (static_cast<double>(i) + 0.8) * line_height(y_label.size), y = (plot_top + plot_bottom) / 2;
    svg << text_element(x, y, y_label.size, "middle", y_label.lines[i], format(" transform='rotate(-90 %.1f %.1f)'", x, y));
  }

  std::vector<PlotSeries> legend;
  if (bars) {
    const double band = plot_height / static_cast<double>(n_bars);
    const PlotSeries& s = panel.series[0];
    bool any_over = false;
    for (std::size_t i = 0; i < n_bars; ++i) {
      const double v = std::isfinite(s.y[i]) ? s.y[i] : 0.0, top = plot_top + band * static_cast<double>(i);
      const bool over = limit && v > panel.bar_limit;
      any_over = any_over || over;
      const double end = px(std::min(v, b.x_max)), zero = px(0.0);
      svg << format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='%s'/>\n", std::min(zero, end),
                    top + 0.15 * band, std::abs(end - zero), 0.7 * band, over ? kOverColour : s.colour.c_str())
          << text_element(plot_left - 6, top + band / 2 + 0.35 * kTickFont, kTickFont, "end", panel.bar_labels[i]);
      if (limit)
        svg << text_element(plot_left + plot_width + 6, top + band / 2 + 0.35 * kTickFont, kTickFont, "start", values[i],
                            over ? format(" fill='%s'", kOverColour) : "");
    }
    if (limit) {
      svg << format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' stroke-width='2' stroke-dasharray='4 2'/>\n",
                    px(panel.bar_limit), plot_top, px(panel.bar_limit), plot_bottom, kOverColour);
      legend.push_back({"limit (100 %)", kOverColour, {}, {}});
      if (any_over) legend.push_back({"over the limit", kOverColour, {}, {}, true});
    }
  } else {
    for (const PlotSeries& s : panel.series) {
      if (s.points) {
        for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
          if (finite_point(s, i))
            svg << format("<circle cx='%.1f' cy='%.1f' r='1.2' fill='%s' fill-opacity='0.5'/>\n", px(s.x[i]), py(s.y[i]),
                          s.colour.c_str());
      } else {
        svg << "<polyline fill='none' stroke-width='1' stroke='" << s.colour << "' points='";
        for (const auto& [x, y] : polyline_points(s, px, py)) svg << format("%.1f,%.1f ", x, y);
        svg << "'/>\n";
      }
      if (!s.label.empty()) legend.push_back(s);
    }
  }
  below += write_legend(svg, legend, x0 + 10, x0 + kPanelWidth - 10, below + 2);
  return below - y0 + 8;
}

}  // namespace

double estimated_text_width(const std::string& text, double font_size) {
  double ems = 0.0;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte & 0xC0) == 0x80) continue;   // a UTF-8 continuation byte: the same character
    if (byte >= 0x80) ems += 0.8;          // ×, √, ², ... : a wide guess
    else if (std::string_view(" .,:;'!|()[]ijlft").find(c) != std::string_view::npos) ems += 0.4;
    else if (std::string_view("mwMW%").find(c) != std::string_view::npos) ems += 1.0;
    else if (std::isupper(byte)) ems += 0.75;
    else ems += 0.64;
  }
  return ems * font_size;
}

PlotPanel joint_limit_panel(const std::string& title, const std::vector<double>& fractions) {
  PlotPanel panel{title, "share of the limit", "", {{"", "#1f77b4", {}, fractions}}, {}};
  panel.bar_limit = 1.0;
  for (std::size_t j = 0; j < fractions.size(); ++j) panel.bar_labels.push_back(format("joint %zu", j + 1));
  return panel;
}

std::string render_panels(const std::string& title, const std::vector<PlotPanel>& panels, int columns) {
  columns = std::max(1, std::min(columns, static_cast<int>(panels.size())));
  const double width = columns * kPanelWidth;
  std::ostringstream body;
  const FittedText fitted = fit_text(title, kFigureTitleFont, width - 20);
  double y = 8 + write_lines(body, fitted, width / 2, 6 + kFigureTitleFont, "middle");
  for (std::size_t row = 0; row * static_cast<std::size_t>(columns) < panels.size(); ++row) {
    double row_height = 0.0;
    for (std::size_t c = 0; c < static_cast<std::size_t>(columns); ++c) {
      const std::size_t i = row * static_cast<std::size_t>(columns) + c;
      if (i < panels.size())
        row_height = std::max(row_height, render_panel(body, panels[i], static_cast<double>(c) * kPanelWidth, y));
    }
    y += row_height;
  }
  return format("<svg xmlns='http://www.w3.org/2000/svg' width='%.0f' height='%.0f' font-family='%s'>\n", width, y, kFont) +
         "<rect width='100%' height='100%' fill='white'/>\n" + body.str() + "</svg>\n";
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace csp
