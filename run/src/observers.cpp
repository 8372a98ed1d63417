#include "csp/run/observers.hpp"

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
    : reference_(std::move(reference)), time_(emulator), tau_max_(emulator.settings().plant.joint_limits.tau_max) {}

void TrackingObserver::on_cycle(const rt::RobotState& state, const rt::CycleInfo&) {
  last_time_ = time_.of(state);
  const Vector7 error = Vector7(state.q.data()) - reference_(last_time_);
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

TrackingObserver::Reference scenario_reference(const rt::Scenario& scenario, const rt::Emulator& emulator) {
  const Vector7 q0(emulator.state().q_d.data());
  return [trajectory = scenario.controller.trajectory, q0](double t) {
    Vector7 q_ref, dq_ref, ddq_ref;
    trajectory->evaluate(q0, t, q_ref, dq_ref, ddq_ref);
    return q_ref;
  };
}

}  // namespace csp::run
