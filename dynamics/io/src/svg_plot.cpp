#include "csp/io/svg_plot.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

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
constexpr double kMapLeft = 80, kMapTop = 66;
constexpr const char* kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";

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

  const double scale = kMaxPlotSize / std::max(x1 - x0, y1 - y0);   // px per data unit, equal on both axes
  const double width = (x1 - x0) * scale, height = (y1 - y0) * scale;
  auto px = [&](double x) { return kMapLeft + (x - x0) * scale; };
  auto py = [&](double y) { return kMapTop + (y1 - y) * scale; };
  const double bar_x = kMapLeft + width + 26, bar_w = 16;
  const double legend_y = kMapTop + height + 70;
  const double total_w = std::max(bar_x + bar_w + 80, 800.0), total_h = legend_y + (f.circles.empty() ? 0 : 22);
  const int decimals = decimals_for(step);

  std::ostringstream s;
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << number(total_w, 0) << "\" height=\"" << number(total_h, 0)
    << "\" viewBox=\"0 0 " << number(total_w, 0) << ' ' << number(total_h, 0) << "\" font-family=\"" << kFont
    << "\" font-size=\"13\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << number(kMapLeft, 0) << "\" y=\"26\" font-size=\"17\" font-weight=\"bold\">" << escape(f.title)
    << "</text>\n"
    << "<text x=\"" << number(kMapLeft, 0) << "\" y=\"46\" font-size=\"12\" fill=\"#444\">" << escape(f.subtitle)
    << "</text>\n";

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
      << "<text x=\"" << number(px(x0) + 6, 1) << "\" y=\"" << number(py(line.y) - 5, 1)
      << "\" font-size=\"11\" fill=\"#444\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\">"
      << escape(line.label) << "</text>\n";
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
    s << "<text x=\"" << number(mx + 10, 1) << "\" y=\"" << number(my + 4, 1)
      << "\" font-size=\"12\" stroke=\"white\" stroke-width=\"3\" paint-order=\"stroke\">" << escape(m.label)
      << "</text>\n";
  }

  // Frame, ticks and labels.
  s << "<rect x=\"" << number(kMapLeft, 1) << "\" y=\"" << number(kMapTop, 1) << "\" width=\"" << number(width, 1)
    << "\" height=\"" << number(height, 1) << "\" fill=\"none\" stroke=\"black\"/>\n";
  for (double v = std::ceil(x0 / step - 1e-9) * step; v <= x1 + 1e-9 * step; v += step) {
    const double x = px(v), value = std::abs(v) < 1e-9 * step ? 0.0 : v;
    s << "<line x1=\"" << number(x, 1) << "\" y1=\"" << number(kMapTop + height, 1) << "\" x2=\"" << number(x, 1)
      << "\" y2=\"" << number(kMapTop + height + 5, 1) << "\" stroke=\"black\"/>"
      << "<text x=\"" << number(x, 1) << "\" y=\"" << number(kMapTop + height + 19, 1) << "\" text-anchor=\"middle\">"
      << number(value, decimals) << "</text>\n";
  }
  for (double v = std::ceil(y0 / step - 1e-9) * step; v <= y1 + 1e-9 * step; v += step) {
    const double y = py(v), value = std::abs(v) < 1e-9 * step ? 0.0 : v;
    s << "<line x1=\"" << number(kMapLeft - 5, 1) << "\" y1=\"" << number(y, 1) << "\" x2=\"" << number(kMapLeft, 1)
      << "\" y2=\"" << number(y, 1) << "\" stroke=\"black\"/>"
      << "<text x=\"" << number(kMapLeft - 8, 1) << "\" y=\"" << number(y + 4, 1) << "\" text-anchor=\"end\">"
      << number(value, decimals) << "</text>\n";
  }
  s << "<text x=\"" << number(kMapLeft + width / 2, 1) << "\" y=\"" << number(kMapTop + height + 42, 1)
    << "\" text-anchor=\"middle\">" << escape(f.x_label) << "</text>\n"
    << "<text transform=\"translate(" << number(kMapLeft - 52, 1) << ' ' << number(kMapTop + height / 2, 1)
    << ") rotate(-90)\" text-anchor=\"middle\">" << escape(f.y_label) << "</text>\n";

  // Colour bar: the same levels as the map, log10 ticks at powers of ten.
  const double level_h = height / kLevels;
  s << "<g shape-rendering=\"crispEdges\">";
  for (int level = 0; level < kLevels; ++level)
    s << "<rect x=\"" << number(bar_x, 1) << "\" y=\"" << number(kMapTop + height - (level + 1) * level_h, 2)
      << "\" width=\"" << number(bar_w, 0) << "\" height=\"" << number(level_h + 0.3, 2) << "\" fill=\""
      << level_colour(level) << "\"/>";
  s << "</g>\n<rect x=\"" << number(bar_x, 1) << "\" y=\"" << number(kMapTop, 1) << "\" width=\"" << number(bar_w, 0)
    << "\" height=\"" << number(height, 1) << "\" fill=\"none\" stroke=\"black\"/>\n";
  auto bar_tick = [&](double count, const std::string& label) {
    const double t = max_count > 1 ? std::log(count) / std::log(static_cast<double>(max_count)) : 1.0;
    const double y = kMapTop + height * (1 - t);
    s << "<line x1=\"" << number(bar_x + bar_w, 1) << "\" y1=\"" << number(y, 1) << "\" x2=\""
      << number(bar_x + bar_w + 4, 1) << "\" y2=\"" << number(y, 1) << "\" stroke=\"black\"/>"
      << "<text x=\"" << number(bar_x + bar_w + 7, 1) << "\" y=\"" << number(y + 4, 1) << "\" font-size=\"12\">"
      << label << "</text>\n";
  };
  double last_power = 1;
  for (double c = 1; c <= static_cast<double>(std::max<std::uint64_t>(max_count, 1)); c *= 10) {
    bar_tick(c, c < 1e4 ? number(c, 0) : "1e" + number(std::log10(c), 0));
    last_power = c;
  }
  if (max_count > 1 && std::log(static_cast<double>(max_count) / last_power) > 0.12 * std::log(static_cast<double>(max_count)))
    bar_tick(static_cast<double>(max_count), std::to_string(max_count));
  s << "<text transform=\"translate(" << number(bar_x + bar_w + 62, 1) << ' ' << number(kMapTop + height / 2, 1)
    << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << escape(f.colour_label) << "</text>\n";

  // Legend of the circles, below the x label.
  double lx = kMapLeft;
  for (const auto& c : f.circles) {
    s << "<line x1=\"" << number(lx, 1) << "\" y1=\"" << number(legend_y - 4, 1) << "\" x2=\"" << number(lx + 30, 1)
      << "\" y2=\"" << number(legend_y - 4, 1) << "\" stroke=\"" << c.colour << "\" stroke-width=\"1.8\""
      << (c.dashed ? " stroke-dasharray=\"8 5\"" : "") << "/>"
      << "<text x=\"" << number(lx + 36, 1) << "\" y=\"" << number(legend_y, 1) << "\" font-size=\"12\">"
      << escape(c.label) << "</text>\n";
    lx += 48 + 6.6 * static_cast<double>(c.label.size());
  }
  s << "</svg>\n";
  return s.str();
}

namespace {

// --- Panels --------------------------------------------------------------------------------------

constexpr double kPanelWidth = 460, kPanelHeight = 230, kPanelLeft = 60, kPanelTop = 30, kPlotWidth = 370,
                 kPlotHeight = 160;

void render_panel(std::ostream& svg, const PlotPanel& panel, double x0, double y0) {
  const bool bars = !panel.bar_labels.empty();
  double x_min = bars ? 0.0 : 1e300, x_max = bars ? 1e-12 : -1e300, y_min = 1e300, y_max = -1e300;
  for (const PlotSeries& s : panel.series)
    for (std::size_t i = 0; i < s.y.size(); ++i) {
      const double x = bars ? s.y[i] : s.x[i];
      x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, s.y[i]),
      y_max = std::max(y_max, s.y[i]);
    }
  if (bars) y_min = 0.0, y_max = static_cast<double>(panel.bar_labels.size());
  if (!(x_max > x_min)) x_max = x_min + 1.0;
  if (!(y_max > y_min)) y_max = y_min + 1.0;
  auto px = [&](double x) { return x0 + kPanelLeft + (x - x_min) / (x_max - x_min) * kPlotWidth; };
  auto py = [&](double y) { return y0 + kPanelTop + kPlotHeight - (y - y_min) / (y_max - y_min) * kPlotHeight; };

  svg << format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' stroke='#444'/>\n", x0 + kPanelLeft,
                y0 + kPanelTop, kPlotWidth, kPlotHeight)
      << format("<text x='%.1f' y='%.1f' font-size='13' text-anchor='middle'>%s</text>\n",
                x0 + kPanelLeft + kPlotWidth / 2, y0 + 18, escape(panel.title).c_str())
      << format("<text x='%.1f' y='%.1f' font-size='11' text-anchor='middle'>%s</text>\n",
                x0 + kPanelLeft + kPlotWidth / 2, y0 + kPanelTop + kPlotHeight + 32, escape(panel.x_label).c_str())
      << format(
             "<text x='%.1f' y='%.1f' font-size='11' text-anchor='middle' transform='rotate(-90 %.1f "
             "%.1f)'>%s</text>\n",
             x0 + 14, y0 + kPanelTop + kPlotHeight / 2, x0 + 14, y0 + kPanelTop + kPlotHeight / 2,
             escape(panel.y_label).c_str());
  const double xs = nice_step((x_max - x_min) / 5.0);  // about five ticks
  for (double t = std::ceil(x_min / xs) * xs; t <= x_max + 1e-12; t += xs)
    svg << format("<text x='%.1f' y='%.1f' font-size='10' text-anchor='middle'>%g</text>\n", px(t),
                  y0 + kPanelTop + kPlotHeight + 14, std::abs(t) < 1e-12 * xs ? 0.0 : t);
  if (bars) {
    for (std::size_t i = 0; i < panel.bar_labels.size(); ++i) {
      const double value = panel.series[0].y[i], top = py(static_cast<double>(panel.bar_labels.size() - i)) + 3;
      svg << format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='%s'/>\n", px(0.0), top,
                    std::max(0.0, px(value) - px(0.0)), kPlotHeight / static_cast<double>(panel.bar_labels.size()) - 6,
                    panel.series[0].colour.c_str())
          << format("<text x='%.1f' y='%.1f' font-size='10'>%s</text>\n", px(0.0) + 4,
                    top + kPlotHeight / static_cast<double>(panel.bar_labels.size()) / 2,
                    escape(panel.bar_labels[i]).c_str());
    }
    return;
  }
  const double ys = nice_step((y_max - y_min) / 5.0);
  for (double t = std::ceil(y_min / ys) * ys; t <= y_max + 1e-12; t += ys)
    svg << format("<text x='%.1f' y='%.1f' font-size='10' text-anchor='end'>%g</text>\n", x0 + kPanelLeft - 4,
                  py(t) + 3, std::abs(t) < 1e-12 * ys ? 0.0 : t);
  double legend_y = y0 + kPanelTop + 12;
  for (const PlotSeries& s : panel.series) {
    if (s.points) {
      for (std::size_t i = 0; i < s.x.size(); ++i)
        svg << format("<circle cx='%.1f' cy='%.1f' r='1.2' fill='%s' fill-opacity='0.5'/>\n", px(s.x[i]), py(s.y[i]),
                      s.colour.c_str());
    } else {
      svg << "<polyline fill='none' stroke-width='1' stroke='" << s.colour << "' points='";
      for (std::size_t i = 0; i < s.x.size(); ++i) svg << format("%.1f,%.1f ", px(s.x[i]), py(s.y[i]));
      svg << "'/>\n";
    }
    if (!s.label.empty())
      svg << format("<text x='%.1f' y='%.1f' font-size='10' fill='%s'>%s</text>\n", x0 + kPanelLeft + 6, legend_y,
                    s.colour.c_str(), escape(s.label).c_str());
    legend_y += 12;
  }
}

}  // namespace

std::string render_panels(const std::string& title, const std::vector<PlotPanel>& panels, int columns) {
  const int rows = (static_cast<int>(panels.size()) + columns - 1) / columns;
  std::ostringstream svg;
  svg << format("<svg xmlns='http://www.w3.org/2000/svg' width='%.0f' height='%.0f' font-family='sans-serif'>\n",
                columns * kPanelWidth, rows * kPanelHeight + 30)
      << "<rect width='100%' height='100%' fill='white'/>\n"
      << format("<text x='%.1f' y='20' font-size='15' text-anchor='middle'>%s</text>\n", columns * kPanelWidth / 2,
                escape(title).c_str());
  for (std::size_t i = 0; i < panels.size(); ++i)
    render_panel(svg, panels[i], static_cast<double>(i % static_cast<std::size_t>(columns)) * kPanelWidth,
                 30 + static_cast<double>(i / static_cast<std::size_t>(columns)) * kPanelHeight);
  svg << "</svg>\n";
  return svg.str();
}


void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace csp
