#include "csp/gap/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "csp/gap/bootstrap.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp::gap {
namespace {

std::vector<double> joint_series(const Eigen::VectorXd& stacked, int joint) {
  std::vector<double> out;
  for (Eigen::Index r = joint; r < stacked.size(); r += kNumJoints) out.push_back(stacked[r]);
  return out;
}

// " (95 % interval 12.3-14.5 %)" for a fraction's interval, or nothing when it has none (a short part).
std::string percent_interval(const std::array<double, 2>& interval, int decimals = 1) {
  if (!std::isfinite(interval[0])) return "";
  return format(" (%.0f %% interval %.*f-%.*f %%)", 100.0 * kIntervalLevel, decimals, 100.0 * interval[0], decimals,
                100.0 * interval[1]);
}

std::string joint_row(const char* name, const Vector7& v) {
  std::string row = format("| %s |", name);
  for (int j = 0; j < kNumJoints; ++j) row.append(" ").append(format("%.3f", v[j])).append(" |");
  return row + "\n";
}

// What to add or check for a structure of each kind.
std::string advice(const UnexplainedStructure& u) {
  if (u.side == kModelInput)
    return "it is in the model's prediction, not the robot: above the motion's band, noise its inputs carry in (log "
           "the acceleration, or smooth the velocity more before differentiating it); within it, check the fitted "
           "causes' warnings";
  if (u.kind == "offset") return "check the torque sensor's zero (sensor_offset)";
  if (u.kind == "time_drift") return "check for a warming sensor or joint (thermal_drift)";
  if (u.kind == "position_periodic") return "check the gear for ripple or cogging (position_ripple)";
  if (u.kind == "velocity_sign" || u.kind == "velocity") return "refit the joint's friction (joint_friction)";
  if (u.kind == "hysteresis") return "add presliding friction (friction_hysteresis)";
  if (u.kind == "acceleration") return "check the rotor inertia (armature) and the inertial parameters";
  if (u.kind == "torque_level") return "check the torque sensor's gain (sensor_gain)";
  if (u.kind == "torque_of_joint")
    return format("check joint %d's torque sensor for crosstalk from joint %d's, or a coupling between them (a cable, "
                  "the link's elasticity)", u.joint, u.from_joint);
  if (u.kind == "velocity_of_joint" || u.kind == "position_of_joint")
    return format("look for a coupling from joint %d (a cable, a hose, the link's elasticity)", u.from_joint);
  if (u.kind == "time_periodic")
    return format("look for a resonance at %.2f Hz: the arm's structure, its mount, the tool, or the controller", u.value);
  if (u.kind == "motion_periodic")
    return "a torque that follows the motion is missing: check the inertial parameters, the friction and the payload";
  if (u.kind == "band")
    return format("look for a vibration near %.2f Hz whose amplitude varies, e.g. a mode of the arm excited more in "
                  "some configurations", u.value);
  return "look for a contact or a push at that time";
}

}  // namespace

std::string finding(const Diagnosis& d) {
  double baseline = 0.0;
  int worst = 0;
  for (int j = 0; j < kNumJoints; ++j) {
    baseline += d.baseline_heldout_rms[j] * d.baseline_heldout_rms[j];
    if (d.baseline_heldout_rms[j] > d.baseline_heldout_rms[worst]) worst = j;
  }
  std::string out = format("The simulator model misses %.3f N m RMS per joint on the held-out part (joint %d most, %.3f N m). ",
                           std::sqrt(baseline / kNumJoints), worst + 1, d.baseline_heldout_rms[worst]);
  if (d.causes.empty()) {
    out += "No effect of the library explains it. ";
  } else {
    out += "Adding ";
    for (std::size_t i = 0; i < d.causes.size(); ++i) out.append(i ? ", " : "").append(d.causes[i]);
    out += format(" removes %.0f %% of its mean square", 100.0 * (1.0 - d.unexplained_fraction)) +
           percent_interval({1.0 - d.unexplained_fraction_interval[1], 1.0 - d.unexplained_fraction_interval[0]}, 0) +
           ". ";
  }
  out += format("Of the %.1f %% left, %.1f %% is the torque sensor's noise, %.1f %% lies in the model's input (noise "
                "its velocity carries into the predicted torque) and %.1f %% is the rest. ",
                100.0 * d.unexplained_fraction, 100.0 * d.unexplained_noise, 100.0 * d.unexplained_model_input,
                100.0 * d.unexplained_rest);
  const auto robot = std::find_if(d.unexplained.begin(), d.unexplained.end(),
                                  [](const UnexplainedStructure& u) { return u.side != kModelInput; });
  if (robot == d.unexplained.end()) {
    out += "Nothing above the noise floor is left in the measured torque.";
  } else {
    out += format("The strongest structure left: joint %d, %s%s, %.3f N m (%.1f times the floor): %s.", robot->joint,
                  robot->kind.c_str(),
                  robot->band_high > 0.0 ? format(" at %.1f-%.1f Hz", robot->band_low, robot->band_high).c_str() : "",
                  robot->size, robot->floor_multiple, advice(*robot).c_str());
  }
  for (const std::string& w : d.warnings) out += " Not physical: " + w + ".";
  if (!d.drifts.empty())
    out += format(" %zu cause(s) and joint(s) drift along the log, first: %s.", d.drifts.size(),
                  d.drifts.front().detail.c_str());
  return out;
}

std::string summary(const Diagnosis& d) {
  std::string out = finding(d) + "\n\nwhere the gap lies (residual = measured - predicted, both parts):\n";
  out += "  joint   rms[Nm]  mean[Nm]  max[Nm]  at t[s]      sign step  corr: q     dq   sign(dq)  ddq   gravity\n";
  for (int j = 0; j < kNumJoints; ++j) {
    const JointGap& g = d.where[j];
    out += format("  %d     %7.3f  %8.3f  %7.3f  %6.2f %-7s %7.3f    %6.2f %6.2f %6.2f %6.2f %6.2f\n", j + 1, g.rms,
                  g.mean, g.max_abs, g.t_at_max, g.part_at_max.c_str(), g.sign_step, g.correlation.at("q"),
                  g.correlation.at("dq"), g.correlation.at("sign_dq"), g.correlation.at("ddq"),
                  g.correlation.at("gravity"));
  }
  out += "effects, each alone (fitted on training, judged on held-out below 5 Hz):\n";
  for (const EffectResult& e : d.effects)
    out += format("  %-20s %3d params  explains %5.1f%% of held-out MS, %5.1f%% below 5 Hz (random regressors: "
                  "%5.1f%%)  %s%s\n",
                  e.name.c_str(), e.parameter_count, 100 * e.explained_fraction, 100 * e.judged_fraction,
                  100 * std::max(0.0, e.null_threshold), e.significant ? "significant" : "-",
                  percent_interval(e.explained_fraction_interval).c_str());
  out += "verdict: ";
  if (d.causes.empty()) out += "no effect of the library explains the gap significantly";
  for (std::size_t i = 0; i < d.causes.size(); ++i) out.append(i ? ", " : "").append(d.causes[i]);
  out += "\nheld-out RMS per joint [Nm]: before";
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.baseline_heldout_rms[j]);
  out += "\n                             after ";
  for (int j = 0; j < kNumJoints; ++j) out += format(" %.3f", d.verdict_heldout_rms_after[j]);
  out += format("\nunexplained: %.1f%% of the held-out mean square%s\n", 100 * d.unexplained_fraction,
                percent_interval(d.unexplained_fraction_interval).c_str());
  for (const UnexplainedStructure& u : d.unexplained) out += "  " + u.detail + "\n";
  out += "noise floor per joint [Nm] (measured torque / model input):";
  for (const NoiseFloor& f : d.noise_floor) out += format(" %.3f/%.3f", f.measured_rms, f.model_input_rms);
  out += "\n";
  for (const std::string& w : d.warnings) out += "warning: " + w + "\n";
  for (const EffectDrift& p : d.drifts) out += "drift: " + p.detail + "\n";
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
      else if (u.kind == "torque_of_joint")
        x.push_back(h.predicted[k][u.from_joint - 1]), axis = format("joint %d's model torque [N m]", u.from_joint);
      else if (u.kind == "velocity_of_joint")
        x.push_back(h.samples.dq[k][u.from_joint - 1]), axis = format("dq%d [rad/s]", u.from_joint);
      else if (u.kind == "position_of_joint")
        x.push_back(h.samples.q[k][u.from_joint - 1]), axis = format("q%d [rad]", u.from_joint);
      else x.push_back(h.samples.t[k]);
    }
    PlotPanel p{format("joint %d: %s", u.joint, u.kind.c_str()), axis, "residual left [N m]", {}, {}};
    p.series.push_back({"held out, after the causes", "#9467bd", x, joint_series(left, j),
                        u.kind != "time_periodic" && u.kind != "band"});
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
  md += finding(d) + "\n\n## Verdict\n\n";
  if (d.causes.empty()) md += "No effect of the library explains the gap significantly.\n\n";
  for (std::size_t i = 0; i < d.causes.size(); ++i)
    md.append(i == 0 ? "Causes, most important first: `" : ", `")
        .append(d.causes[i])
        .append(i + 1 == d.causes.size() ? "`.\n\n" : "`");
  md += "| held-out RMS [N m] | J1 | J2 | J3 | J4 | J5 | J6 | J7 |\n|---|---|---|---|---|---|---|---|\n";
  md +=
      joint_row("simulator model", d.baseline_heldout_rms) + joint_row("with the causes", d.verdict_heldout_rms_after);
  md += format("\nUnexplained: %.1f %% of the held-out mean square remains%s: %.1f %% the torque sensor's noise, %.1f "
               "%% in the model's input, %.1f %% the rest.\n\n",
               100 * d.unexplained_fraction, percent_interval(d.unexplained_fraction_interval).c_str(), 100 * d.unexplained_noise, 100 * d.unexplained_model_input,
               100 * d.unexplained_rest);
  for (const std::string& w : d.warnings) md += "**Not physical:** " + w + ".\n\n";
  for (const EffectDrift& p : d.drifts) md += "**Drift:** " + p.detail + ".\n\n";
  for (const UnexplainedStructure& u : d.unexplained) md += "- " + u.detail + "\n";
  if (!d.unexplained.empty()) md += "\n![unexplained](unexplained.svg)\n\n";
  md += "![torque](torque_heldout.svg)\n\n## Effects, each alone\n\n";
  md += "| effect | parameters | explained | below 5 Hz (judged) | random regressors | significant | joints |\n"
        "|---|---|---|---|---|---|---|\n";
  for (const EffectResult& e : d.effects) {
    std::string joints;
    for (int j : e.joints) joints.append(joints.empty() ? "" : ",").append(std::to_string(j));
    md += format("| %s | %d | %.1f %%%s | %.1f %% | %.1f %% | %s | %s |\n", e.name.c_str(), e.parameter_count,
                 100 * e.explained_fraction, percent_interval(e.explained_fraction_interval).c_str(), 100 * e.judged_fraction, 100 * std::max(0.0, e.null_threshold),
                 e.significant ? "yes" : "no", joints.c_str());
  }
  md += "\n![ranking](effect_ranking.svg)\n\n## Where the gap lies\n\n```\n" + summary(d) + "```\n\n";
  md += "![residual vs velocity](residual_vs_velocity.svg)\n\n## Fitted parameters of the causes\n\n```json\n" +
        d.verdict_params.dump(2) + "\n```\n";
  write_text_file((folder / "report.md").string(), md);
}

}  // namespace csp::gap
