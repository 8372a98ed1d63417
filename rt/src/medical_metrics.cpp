#include "csp/rt/medical_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "csp/io/svg_plot.hpp"

namespace csp::rt {
namespace {

constexpr double kInContact = 1e-3;   // [N] a true pressing force above this is contact

Vector3 head3(const std::array<double, 6>& a) { return Vector3(a[0], a[1], a[2]); }

double rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

double max_of(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

}  // namespace

MedicalRecorder::MedicalRecorder(const Scenario& scenario, const Emulator& emulator,
                                 std::shared_ptr<const MedicalStatus> status)
    : emulator_(emulator), scene_(scenario.emulator.scene), bone_(scenario.bone), status_(std::move(status)), controller_(scenario.controller.medical) {
  if (!scene_) throw std::invalid_argument("medical metrics need a scenario with a scene");
  samples_.reserve(static_cast<std::size_t>(std::min(scenario.duration, 600.0) * 1000.0) + 1);
}

void MedicalRecorder::add(const RobotState& state, double t) {
  Sample s;
  s.t = t;
  s.true_force = emulator_.contact().O_F_tool.head<3>();   // the scene's contacts and the tissue's
  s.penetration = emulator_.contact().max_penetration;
  s.estimated_force = head3(state.O_F_ext_hat_K);
  s.tcp = Vector3(state.O_T_EE[12], state.O_T_EE[13], state.O_T_EE[14]);
  s.axis = Vector3(state.O_T_EE[8], state.O_T_EE[9], state.O_T_EE[10]);
  s.depth = 0.0;
  if (const auto* hole = std::get_if<BurrHole>(&scene_->task)) s.depth = (hole->entry - s.tcp).dot(hole->axis);
  if (const auto* pivot = std::get_if<RcmPivot>(&scene_->task)) s.depth = (s.tcp - pivot->trocar).dot(s.axis);
  if (const auto* scan = std::get_if<UltrasoundScan>(&scene_->task)) s.depth = (s.tcp - scan->start).dot(scan->tool_axis);
  samples_.push_back(s);
}

// The push direction: the tool axis of the scan, the drill's feed direction, the shaft's axis.
double MedicalRecorder::axial(const Vector3& force, const Sample& s) const {
  if (const auto* scan = std::get_if<UltrasoundScan>(&scene_->task)) return force.dot(scan->tool_axis);
  if (const auto* hole = std::get_if<BurrHole>(&scene_->task)) return -force.dot(hole->axis);
  return force.dot(s.axis);
}

double MedicalRecorder::path_error(const Sample& s) const {
  if (const auto* scan = std::get_if<UltrasoundScan>(&scene_->task)) {
    const Vector3 line = (scan->end - scan->start).normalized(), n = scan->tool_axis;
    const Vector3 d = s.tcp - scan->start;
    return (d - d.dot(line) * line - d.dot(n) * n).norm();
  }
  if (const auto* hole = std::get_if<BurrHole>(&scene_->task)) return line_offset_from(hole->entry, hole->axis, s.tcp).norm();
  const auto& pivot = std::get<RcmPivot>(scene_->task);
  return line_offset_from(s.tcp, s.axis, pivot.trocar).norm();
}

std::vector<MedicalMetric> MedicalRecorder::metrics() const {
  std::vector<MedicalMetric> out;
  std::vector<double> estimate_error, path;
  for (const Sample& s : samples_) estimate_error.push_back((s.estimated_force - s.true_force).norm());

  if (std::holds_alternative<UltrasoundScan>(scene_->task)) {
    std::vector<double> force_error, indentation;
    int losses = 0;
    bool touched = false, in_contact = false;
    for (const Sample& s : samples_) {
      const double f = axial(s.true_force, s);
      const bool contact = f > kInContact;
      if (touched && in_contact && !contact) ++losses;
      touched = touched || contact;
      in_contact = contact;
      if (s.t >= controller_.settle) {
        force_error.push_back(f - controller_.desired_force);
        path.push_back(path_error(s));
        indentation.push_back(s.penetration);
      }
    }
    out.push_back({"contact force RMS error (scan)", rms(force_error), "N"});
    out.push_back({"contact losses", static_cast<double>(losses), ""});
    out.push_back({"path error RMS (scan)", 1e3 * rms(path), "mm"});
    out.push_back({"path error max (scan)", 1e3 * max_of(path), "mm"});
    out.push_back({"skin indentation RMS (scan)", 1e3 * rms(indentation), "mm"});
    out.push_back({"skin indentation max (scan)", 1e3 * max_of(indentation), "mm"});
  } else if (std::holds_alternative<RcmPivot>(scene_->task)) {
    std::vector<double> force;
    for (const Sample& s : samples_)
      if (s.depth > 0.0) {
        path.push_back(path_error(s));
        force.push_back(s.true_force.norm());
      }
    out.push_back({"RCM deviation RMS", 1e3 * rms(path), "mm"});
    out.push_back({"RCM deviation max", 1e3 * max_of(path), "mm"});
    out.push_back({"trocar force RMS", rms(force), "N"});
    out.push_back({"trocar force max", max_of(force), "N"});
  } else {
    std::vector<double> thrust, depth;
    for (const Sample& s : samples_) {
      thrust.push_back(axial(s.true_force, s));
      depth.push_back(s.depth);
    }
    const double thickness = bone_ ? bone_->layer().settings().thickness : 0.0;
    // NaN: it did not happen.
    const double breakthrough = bone_ ? bone_->breakthrough_time().value_or(NAN) : NAN;
    const double detected = status_ ? status_->breakthrough_detected_at.value_or(NAN) : NAN;
    out.push_back({"thrust max", max_of(thrust), "N"});
    out.push_back({"breakthrough time", breakthrough, "s"});
    out.push_back({"breakthrough detected at", detected, "s"});
    out.push_back({"overshoot past the bone", 1e3 * std::max(0.0, max_of(depth) - thickness), "mm"});
    out.push_back({"bone left under the bit", bone_ ? 1e3 * (thickness - bone_->layer().removed()) : NAN, "mm"});
  }
  out.push_back({"force estimate error RMS (|O_F_ext_hat_K - true|)", rms(estimate_error), "N"});
  out.push_back({"force estimate error max", max_of(estimate_error), "N"});
  return out;
}

void MedicalRecorder::write_figures(const std::string& directory) const {
  std::filesystem::create_directories(directory);
  PlotSeries true_force{"true", "#1f77b4", {}, {}}, estimated{"estimated (O_F_ext_hat_K)", "#d62728", {}, {}};
  PlotSeries path{"path error", "#2ca02c", {}, {}}, depth{"depth along the task's axis", "#9467bd", {}, {}};
  PlotSeries penetration{"scene contact penetration", "#ff7f0e", {}, {}};
  for (const Sample& s : samples_) {
    true_force.x.push_back(s.t);
    true_force.y.push_back(axial(s.true_force, s));
    estimated.x.push_back(s.t);
    estimated.y.push_back(axial(s.estimated_force, s));
    path.x.push_back(s.t);
    path.y.push_back(1e3 * path_error(s));
    depth.x.push_back(s.t);
    depth.y.push_back(1e3 * s.depth);
    penetration.x.push_back(s.t);
    penetration.y.push_back(1e3 * s.penetration);
  }
  const std::string name = scene_->name;
  write_text_file(directory + "/force.svg",
                  render_panels(name + ": contact force along the tool axis",
                                {{"force vs time", "t [s]", "force [N]", {true_force, estimated}, {}}}, 1));
  write_text_file(directory + "/path.svg",
                  render_panels(name + ": distance from the task's path (scan line, burr axis, trocar)",
                                {{"path error vs time", "t [s]", "error [mm]", {path}, {}}}, 1));
  write_text_file(directory + "/penetration.svg",
                  render_panels(name + ": depth along the tool axis (below the skin line, burr entry, trocar)",
                                {{"depth vs time", "t [s]", "depth [mm]", {depth}, {}},
                                 {"penetration vs time", "t [s]", "penetration [mm]", {penetration}, {}}},
                                1));
}

}  // namespace csp::rt
