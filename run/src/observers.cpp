#include "csp/run/observers.hpp"

#include <filesystem>
#include <stdexcept>

#include "csp/dynamics/limits.hpp"
#include "csp/io/svg_plot.hpp"

namespace csp::run {

CsvLogObserver::CsvLogObserver(const std::string& path, const rt::Emulator& emulator) : log_(path) {
  log_.write(emulator.state(), rt::CycleInfo{});   // the state the motion starts from
}

std::unique_ptr<CsvLogObserver> observe_csv_log(Run& run, const std::string& path) {
  if (path.empty()) return nullptr;
  auto log = std::make_unique<CsvLogObserver>(path, run.emulator());
  run.observe(*log);
  return log;
}

TrackingObserver::TrackingObserver(Reference reference, const rt::Emulator& emulator)
    : reference_(std::move(reference)),
      time_(emulator),
      tau_max_(emulator.settings().plant.joint_limits.tau_max),
      limits_(emulator.settings().plant.joint_limits) {}

void TrackingObserver::on_cycle(const rt::RobotState& state, const rt::CycleInfo&) {
  last_time_ = time_.of(state);
  const Vector7 q(state.q.data());
  const Vector7 q_ref = reference_ ? reference_(last_time_) : q;
  const Vector7 error = q - q_ref;
  if (keep_figures_) {
    keep_limit_use(state);
    if (cycles_ % 10 == 0)
      figure_samples_.push_back({last_time_, q, q_ref, Vector7(state.tau_J.data()),
                                 Vector3(state.O_T_EE[12], state.O_T_EE[13], state.O_T_EE[14])});
  }
  squared_error_ += error.cwiseAbs2();
  max_error_ = max_error_.cwiseMax(error.cwiseAbs());
  max_tau_ext_ = max_tau_ext_.cwiseMax(Vector7(state.tau_ext_hat_filtered.data()).cwiseAbs());
  peak_tau_J_fraction_ = peak_tau_J_fraction_.cwiseMax(Vector7(state.tau_J.data()).cwiseAbs().cwiseQuotient(tau_max_));
  ++cycles_;
}

Vector7 TrackingObserver::rms_error() const {
  if (cycles_ == 0) return Vector7::Zero();
  return (squared_error_ / static_cast<double>(cycles_)).cwiseSqrt();
}

void TrackingObserver::keep_limit_use(const rt::RobotState& state) {
  const Vector7 q(state.q.data()), dq(state.dq.data()), tau_J(state.tau_J.data()), tau_J_d(state.tau_J_d.data());
  const Vector7 middle = (limits_.q_max + limits_.q_min) / 2, half_range = (limits_.q_max - limits_.q_min) / 2;
  position_use_ = position_use_.cwiseMax((q - middle).cwiseAbs().cwiseQuotient(half_range));
  const Vector7 upper = limits_.dq_upper(q), lower = limits_.dq_lower(q);
  for (int j = 0; j < kNumJoints; ++j) {
    const double bound = dq[j] >= 0 ? upper[j] : -lower[j];   // a bound at zero: any motion is over
    velocity_use_[j] = std::max(velocity_use_[j], dq[j] == 0.0 ? 0.0 : std::abs(dq[j]) / std::max(bound, 1e-9));
  }
  torque_use_ = torque_use_.cwiseMax(tau_J.cwiseAbs().cwiseQuotient(limits_.tau_max));
  power_use_ = std::max(power_use_, joint_power(tau_J, dq) / limits_.power_max);
  if (previous_) {
    const double dt = (state.time - previous_->time).toSec();
    if (dt > 0.0) {
      const Vector7 ddq = (dq - Vector7(previous_->dq.data())) / dt;
      acceleration_use_ = acceleration_use_.cwiseMax(ddq.cwiseAbs().cwiseQuotient(limits_.ddq_max));
      if (previous_ddq_)
        jerk_use_ = jerk_use_.cwiseMax(((ddq - *previous_ddq_) / dt).cwiseAbs().cwiseQuotient(limits_.dddq_max));
      torque_rate_use_ = torque_rate_use_.cwiseMax(
          ((tau_J_d - Vector7(previous_->tau_J_d.data())) / dt).cwiseAbs().cwiseQuotient(limits_.dtau_max));
      previous_ddq_ = ddq;
    }
  }
  previous_ = state;
}

namespace {

std::vector<double> as_vector(const Vector7& v) { return {v.data(), v.data() + kNumJoints}; }

// One panel per joint over time: `series` picks each sample's values, one line each.
std::vector<PlotPanel> joint_panels(const std::vector<PlotSeries>& styles, const std::string& y_label,
                                    const std::function<std::vector<double>(int joint, std::size_t sample)>& values,
                                    std::size_t samples, const std::vector<double>& times) {
  std::vector<PlotPanel> panels;
  for (int j = 0; j < kNumJoints; ++j) {
    PlotPanel panel{format("joint %d", j + 1), "t [s]", y_label, styles, {}};
    for (std::size_t k = 0; k < samples; ++k) {
      const std::vector<double> v = values(j, k);
      for (std::size_t s = 0; s < styles.size(); ++s) panel.series[s].x.push_back(times[k]), panel.series[s].y.push_back(v[s]);
    }
    panels.push_back(panel);
  }
  return panels;
}

}  // namespace

void TrackingObserver::write_figures(const std::string& directory, const std::string& name) const {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error || !std::filesystem::is_directory(directory))
    throw std::runtime_error("cannot create the report directory " + directory);
  const std::vector<FigureSample>& f = figure_samples_;
  std::vector<double> t;
  for (const FigureSample& s : f) t.push_back(s.t);
  const bool reference = static_cast<bool>(reference_);

  std::vector<PlotSeries> positions{{"q (measured)", "#1f77b4", {}, {}}};
  if (reference) positions.push_back({"q_ref (the scenario's trajectory)", "#d62728", {}, {}});
  write_text_file(directory + "/joint_positions.svg",
                  render_panels(name + ": joint positions",
                                joint_panels(positions, "q [rad]", [&](int j, std::size_t k) {
                                  return std::vector<double>{f[k].q[j], f[k].q_ref[j]};
                                }, f.size(), t), 2));
  if (reference)
    write_text_file(directory + "/tracking_error.svg",
                    render_panels(name + ": tracking error q - q_ref",
                                  joint_panels({{"", "#1f77b4", {}, {}}}, "error [mrad]", [&](int j, std::size_t k) {
                                    return std::vector<double>{1e3 * (f[k].q[j] - f[k].q_ref[j])};
                                  }, f.size(), t), 2));
  write_text_file(directory + "/joint_torques.svg",
                  render_panels(name + ": measured joint torques tau_J and their limits",
                                joint_panels({{"tau_J", "#1f77b4", {}, {}}, {"+tau_max", "#d62728", {}, {}},
                                              {"-tau_max", "#ff7f0e", {}, {}}},
                                             "tau_J [N m]", [&](int j, std::size_t k) {
                                               return std::vector<double>{f[k].tau_J[j], limits_.tau_max[j], -limits_.tau_max[j]};
                                             }, f.size(), t), 2));

  std::vector<PlotPanel> usage{joint_limit_panel("position (of half the range)", as_vector(position_use_)),
                               joint_limit_panel("velocity", as_vector(velocity_use_)),
                               joint_limit_panel("acceleration (differences of dq)", as_vector(acceleration_use_)),
                               joint_limit_panel("jerk (differences of dq)", as_vector(jerk_use_)),
                               joint_limit_panel("torque tau_J", as_vector(torque_use_)),
                               joint_limit_panel("torque rate (of tau_J_d)", as_vector(torque_rate_use_)),
                               joint_limit_panel("power (sum of the joints' positive powers)", {power_use_})};
  usage.back().bar_labels = {"arm"};
  write_text_file(directory + "/limits.svg", render_panels(name + ": limit usage per joint", usage, 2));

  std::vector<PlotPanel> path{{"side view (x, z)", "x [m]", "z [m]", {{"EE path (O_T_EE)", "#1f77b4", {}, {}}}, {}},
                              {"top view (x, y)", "x [m]", "y [m]", {{"EE path (O_T_EE)", "#1f77b4", {}, {}}}, {}}};
  for (const FigureSample& s : f) {
    path[0].series[0].x.push_back(s.tcp.x()), path[0].series[0].y.push_back(s.tcp.z());
    path[1].series[0].x.push_back(s.tcp.x()), path[1].series[0].y.push_back(s.tcp.y());
  }
  if (!f.empty())
    for (int v = 0; v < 2; ++v)
      path[v].series.push_back({"start", "#2ca02c", {path[v].series[0].x.front()}, {path[v].series[0].y.front()}, true});
  write_text_file(directory + "/ee_path.svg", render_panels(name + ": end-effector path", path, 2));
}

TrackingObserver::Reference scenario_reference(const rt::Scenario& scenario, const rt::Emulator& emulator) {
  const Vector7 q0(emulator.state().q_d.data());
  return [trajectory = scenario.controller.trajectory, q0](double t) {
    Vector7 q_ref, dq_ref, ddq_ref;
    trajectory->evaluate(q0, t, q_ref, dq_ref, ddq_ref);
    return q_ref;
  };
}

}  // namespace csp::run
