#include "csp/gap/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace csp::gap {
namespace {

std::string format(const char* pattern, auto... values) {
  std::string out(static_cast<std::size_t>(std::max(0, std::snprintf(nullptr, 0, pattern, values...))), '\0');
  std::snprintf(out.data(), out.size() + 1, pattern, values...);
  return out;
}

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  return out;
}

// A "nice" tick step for the range (1, 2 or 5 times a power of ten, about 5 ticks).
double tick_step(double range) {
  const double raw = range / 5.0, power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * power >= raw) return m * power;
  return 10.0 * power;
}

constexpr double kPanelWidth = 460, kPanelHeight = 230, kLeft = 60, kTop = 30, kPlotWidth = 370, kPlotHeight = 160;

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
  auto px = [&](double x) { return x0 + kLeft + (x - x_min) / (x_max - x_min) * kPlotWidth; };
  auto py = [&](double y) { return y0 + kTop + kPlotHeight - (y - y_min) / (y_max - y_min) * kPlotHeight; };

  svg << format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' stroke='#444'/>\n", x0 + kLeft,
                y0 + kTop, kPlotWidth, kPlotHeight)
      << format("<text x='%.1f' y='%.1f' font-size='13' text-anchor='middle'>%s</text>\n", x0 + kLeft + kPlotWidth / 2,
                y0 + 18, escape(panel.title).c_str())
      << format("<text x='%.1f' y='%.1f' font-size='11' text-anchor='middle'>%s</text>\n", x0 + kLeft + kPlotWidth / 2,
                y0 + kTop + kPlotHeight + 32, escape(panel.x_label).c_str())
      << format(
             "<text x='%.1f' y='%.1f' font-size='11' text-anchor='middle' transform='rotate(-90 %.1f "
             "%.1f)'>%s</text>\n",
             x0 + 14, y0 + kTop + kPlotHeight / 2, x0 + 14, y0 + kTop + kPlotHeight / 2, escape(panel.y_label).c_str());
  const double xs = tick_step(x_max - x_min);
  for (double t = std::ceil(x_min / xs) * xs; t <= x_max + 1e-12; t += xs)
    svg << format("<text x='%.1f' y='%.1f' font-size='10' text-anchor='middle'>%g</text>\n", px(t),
                  y0 + kTop + kPlotHeight + 14, std::abs(t) < 1e-12 * xs ? 0.0 : t);
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
  const double ys = tick_step(y_max - y_min);
  for (double t = std::ceil(y_min / ys) * ys; t <= y_max + 1e-12; t += ys)
    svg << format("<text x='%.1f' y='%.1f' font-size='10' text-anchor='end'>%g</text>\n", x0 + kLeft - 4, py(t) + 3,
                  std::abs(t) < 1e-12 * ys ? 0.0 : t);
  double legend_y = y0 + kTop + 12;
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
      svg << format("<text x='%.1f' y='%.1f' font-size='10' fill='%s'>%s</text>\n", x0 + kLeft + 6, legend_y,
                    s.colour.c_str(), escape(s.label).c_str());
    legend_y += 12;
  }
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::vector<double> joint_series(const Eigen::VectorXd& stacked, int joint) {
  std::vector<double> out;
  for (Eigen::Index r = joint; r < stacked.size(); r += kNumJoints) out.push_back(stacked[r]);
  return out;
}

std::string joint_row(const char* name, const Vector7& v) {
  std::string row = format("| %s |", name);
  for (int j = 0; j < kNumJoints; ++j) row.append(" ").append(format("%.3f", v[j])).append(" |");
  return row + "\n";
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

std::string summary(const Diagnosis& d) {
  std::string out = "where the gap lies (residual = measured - predicted, both parts):\n";
  out += "  joint   rms[Nm]  mean[Nm]  max[Nm]  at t[s]      sign step  corr: q     dq   sign(dq)  ddq   gravity\n";
  for (int j = 0; j < kNumJoints; ++j) {
    const JointGap& g = d.where[j];
    out += format("  %d     %7.3f  %8.3f  %7.3f  %6.2f %-7s %7.3f    %6.2f %6.2f %6.2f %6.2f %6.2f\n", j + 1, g.rms,
                  g.mean, g.max_abs, g.t_at_max, g.part_at_max.c_str(), g.sign_step, g.correlation.at("q"),
                  g.correlation.at("dq"), g.correlation.at("sign_dq"), g.correlation.at("ddq"),
                  g.correlation.at("gravity"));
  }
  out += "effects, each alone (fitted on training, judged on held-out):\n";
  for (const EffectResult& e : d.effects)
    out += format("  %-20s %3d params  explains %5.1f%% of held-out MS (random regressors: %5.1f%%)  %s\n",
                  e.name.c_str(), e.parameter_count, 100 * e.explained_fraction, 100 * std::max(0.0, e.null_threshold),
                  e.significant ? "significant" : "-");
  out += "verdict: ";
  if (d.causes.empty()) out += "no effect of the library explains the gap significantly";
  for (std::size_t i = 0; i < d.causes.size(); ++i) out.append(i ? ", " : "").append(d.causes[i]);
  out += format("\nheld-out RMS per joint [Nm]: before");
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.baseline_heldout_rms[j]);
  out += "\n                             after ";
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.verdict_heldout_rms_after[j]);
  out += format("\nunexplained: %.1f%% of the held-out mean square\n", 100 * d.unexplained_fraction);
  return out;
}

void write_report(const std::string& dir, const Diagnosis& d, const std::string& command_line) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir)) throw std::runtime_error("cannot create report directory " + dir);
  const Part& h = d.heldout;
  const Eigen::VectorXd measured = stack(h.samples.tau), predicted = stack(h.predicted);
  const Eigen::VectorXd corrected = predicted + d.verdict_heldout_torque;

  std::vector<PlotPanel> torque, velocity;
  for (int j = 0; j < kNumJoints; ++j) {
    const std::vector<double> t = h.samples.t;
    PlotPanel p{format("joint %d", j + 1), "t [s]", "torque [N m]", {}, {}};
    p.series.push_back({"measured", "#111111", t, joint_series(measured, j)});
    p.series.push_back({"simulator model", "#d62728", t, joint_series(predicted, j)});
    if (!d.causes.empty()) p.series.push_back({"model + selected effects", "#1f77b4", t, joint_series(corrected, j)});
    torque.push_back(p);
    PlotPanel v{format("joint %d", j + 1), "dq [rad/s]", "residual [N m]", {}, {}};
    for (const Part* part : {&d.train, &d.heldout}) {
      std::vector<double> dq;
      for (const Vector7& s : part->samples.dq) dq.push_back(s[j]);
      v.series.push_back({part == &d.train ? "training" : "held out", part == &d.train ? "#1f77b4" : "#ff7f0e", dq,
                          joint_series(part->residual, j), true});
    }
    velocity.push_back(v);
  }
  PlotPanel ranking{"held-out mean square explained, each effect alone", "fraction", "", {{"", "#2ca02c", {}, {}}}, {}};
  for (const EffectResult& e : d.effects) {
    ranking.series[0].y.push_back(e.explained_fraction);
    ranking.bar_labels.push_back(
        format("%s %.1f%%%s", e.name.c_str(), 100 * e.explained_fraction, e.significant ? " *" : ""));
  }
  write_text(fs::path(dir) / "torque_heldout.svg",
             render_panels("Held-out part: measured vs predicted joint torque", torque, 2));
  write_text(fs::path(dir) / "residual_vs_velocity.svg",
             render_panels("Residual (measured - predicted) vs joint velocity", velocity, 2));
  write_text(fs::path(dir) / "effect_ranking.svg", render_panels("Effect ranking (* = significant)", {ranking}, 1));

  std::string md = "# Sim-to-real gap report\n\n`" + command_line + "`\n\n";
  md += format("Training: %s (%zu samples); held out: %s (%zu samples).\n\n", d.train.samples.source.c_str(),
               d.train.samples.size(), d.heldout.samples.source.c_str(), d.heldout.samples.size());
  md += "## Verdict\n\n";
  if (d.causes.empty()) md += "No effect of the library explains the gap significantly.\n\n";
  for (std::size_t i = 0; i < d.causes.size(); ++i)
    md.append(i == 0 ? "Causes, most important first: `" : ", `")
        .append(d.causes[i])
        .append(i + 1 == d.causes.size() ? "`.\n\n" : "`");
  md += "| held-out RMS [N m] | J1 | J2 | J3 | J4 | J5 | J6 | J7 |\n|---|---|---|---|---|---|---|---|\n";
  md +=
      joint_row("simulator model", d.baseline_heldout_rms) + joint_row("with the causes", d.verdict_heldout_rms_after);
  md += format("\nUnexplained: %.1f %% of the held-out mean square remains.\n\n", 100 * d.unexplained_fraction);
  md += "![torque](torque_heldout.svg)\n\n## Effects, each alone\n\n";
  md += "| effect | parameters | explained | random regressors | significant | joints |\n|---|---|---|---|---|---|\n";
  for (const EffectResult& e : d.effects) {
    std::string joints;
    for (int j : e.joints) joints.append(joints.empty() ? "" : ",").append(std::to_string(j));
    md += format("| %s | %d | %.1f %% | %.1f %% | %s | %s |\n", e.name.c_str(), e.parameter_count,
                 100 * e.explained_fraction, 100 * std::max(0.0, e.null_threshold), e.significant ? "yes" : "no",
                 joints.c_str());
  }
  md += "\n![ranking](effect_ranking.svg)\n\n## Where the gap lies\n\n```\n" + summary(d) + "```\n\n";
  md += "![residual vs velocity](residual_vs_velocity.svg)\n\n## Fitted parameters of the causes\n\n```json\n" +
        d.verdict_params.dump(2) + "\n```\n";
  write_text(fs::path(dir) / "report.md", md);
}

}  // namespace csp::gap
