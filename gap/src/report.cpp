#include "csp/gap/report.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "csp/io/svg_plot.hpp"

namespace csp::gap {
namespace {

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
  out += "\nheld-out RMS per joint [Nm]: before";
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.baseline_heldout_rms[j]);
  out += "\n                             after ";
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.verdict_heldout_rms_after[j]);
  out += format("\nunexplained: %.1f%% of the held-out mean square\n", 100 * d.unexplained_fraction);
  for (const UnexplainedStructure& u : d.unexplained) out += "  " + u.detail + "\n";
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
  // What stays unexplained: the held-out residual after the causes against the variable of its
  // strongest structure, one panel per localised joint.
  const Eigen::VectorXd left = h.residual - d.verdict_heldout_torque;
  std::vector<PlotPanel> unexplained;
  for (const UnexplainedStructure& u : d.unexplained) {
    const int j = u.joint - 1;
    std::vector<double> x;
    std::string axis = "t [s]";
    for (std::size_t k = 0; k < h.samples.size(); ++k) {
      if (u.kind == "position_periodic") x.push_back(h.samples.q[k][j]), axis = format("q%d [rad]", u.joint);
      else if (u.kind == "velocity_sign" || u.kind == "velocity" || u.kind == "hysteresis")
        x.push_back(h.samples.dq[k][j]), axis = format("dq%d [rad/s]", u.joint);
      else if (u.kind == "acceleration") x.push_back(h.samples.ddq[k][j]), axis = format("ddq%d [rad/s^2]", u.joint);
      else if (u.kind == "torque_level") x.push_back(h.predicted[k][j]), axis = "model torque [N m]";
      else x.push_back(h.samples.t[k]);
    }
    PlotPanel p{format("joint %d: %s", u.joint, u.kind.c_str()), axis, "residual left [N m]", {}, {}};
    p.series.push_back({"held out, after the causes", "#9467bd", x, joint_series(left, j), u.kind != "time_periodic"});
    unexplained.push_back(p);
  }
  const fs::path folder(dir);
  if (!unexplained.empty())
    write_text_file((folder / "unexplained.svg").string(),
                    render_panels("What stays unexplained, by joint and kind", unexplained, 2));
  write_text_file((folder / "torque_heldout.svg").string(),
                  render_panels("Held-out part: measured vs predicted joint torque", torque, 2));
  write_text_file((folder / "residual_vs_velocity.svg").string(),
                  render_panels("Residual (measured - predicted) vs joint velocity", velocity, 2));
  write_text_file((folder / "effect_ranking.svg").string(),
                  render_panels("Effect ranking (* = significant)", {ranking}, 1));

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
  for (const UnexplainedStructure& u : d.unexplained) md += "- " + u.detail + "\n";
  if (!d.unexplained.empty()) md += "\n![unexplained](unexplained.svg)\n\n";
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
  write_text_file((folder / "report.md").string(), md);
}

}  // namespace csp::gap
