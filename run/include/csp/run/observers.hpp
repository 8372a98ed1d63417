// The observers of a run (run.hpp): logs, tracking, medical metrics, progress. Each sees the
// states in order and keeps what it measures; a log observer throws when its file cannot be
// written (the run then ends as its duration would).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <vector>
#include <string>

#include "csp/bridge/lcm_log.hpp"
#include "csp/dynamics/progress.hpp"
#include "csp/rt/csv_log.hpp"
#include "csp/rt/medical_metrics.hpp"
#include "csp/run/run.hpp"

namespace csp::run {

// Motion time [s] of a state: robot time since the state the run started from.
class MotionTime {
 public:
  explicit MotionTime(const rt::Emulator& emulator) : start_ms_(emulator.state().time.toMSec()) {}
  double of(const rt::RobotState& state) const { return static_cast<double>(state.time.toMSec() - start_ms_) * 1e-3; }

 private:
  uint64_t start_ms_;
};

// The per-cycle CSV log (docs/joint-log.md), from the state the run starts from.
class CsvLogObserver : public Observer {
 public:
  CsvLogObserver(const std::string& path, const rt::Emulator& emulator);
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override { log_.write(state, cycle); }
  const rt::CsvLog& log() const { return log_; }
  void flush() { log_.flush(); }   // at the run's end: throws JointLogError if the last rows cannot be written

 private:
  rt::CsvLog log_;
};

// Every state of a run kept in memory as joint-log rows, from the state the run starts from (the
// page of `csp view --scenario`, a campaign's per-run `csp gap` diagnosis).
class JointLogRecorder : public Observer {
 public:
  explicit JointLogRecorder(const rt::Emulator& emulator) { rt::append_state(log_, emulator.state(), false); }
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override {
    rt::append_state(log_, state, cycle.command_received);
  }
  JointLog& log() { return log_; }

 private:
  JointLog log_;
};

// The CSV log at `path` observing `run` from now on; none for an empty path (a command's option).
std::unique_ptr<CsvLogObserver> observe_csv_log(Run& run, const std::string& path);

// A run of the built-in controller as an LCM log (csp replay, csp log export, lcm-spy); `mode`:
// the controller's. (A serve run logs what crosses its bus: bridge/serve.hpp, can/serve.hpp.)
class LcmLogObserver : public Observer {
 public:
  LcmLogObserver(const std::string& path, const Run& run, rt::ControlMode mode)
      : recorder_(path, run.scenario(), run.emulator(), mode) {}
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override { recorder_.record(state, cycle); }
  uint64_t events() const { return recorder_.log().events(); }
  void flush() { recorder_.flush(); }   // at the run's end: throws std::runtime_error if the last events cannot be written

 private:
  bridge::EmulateLogRecorder recorder_;
};

// The measured q against a reference q_ref(t) (t: motion time [s]), joint by joint; with the peaks
// of the estimated external torque and of the sensed torque against its limit. An empty reference
// (a scene's task, not a joint trajectory) leaves the tracking error at zero.
class TrackingObserver : public Observer {
 public:
  using Reference = std::function<Vector7(double t)>;
  TrackingObserver(Reference reference, const rt::Emulator& emulator);

  // `csp emulate --report DIR`: keep every 10th state for the figures and each limit's peak use
  // over every state; write_figures then writes joint_positions.svg, tracking_error.svg (with a
  // reference), joint_torques.svg (tau_J with +-tau_max), limits.svg and ee_path.svg into
  // `directory` (created), each titled after `name`.
  void keep_figures() { keep_figures_ = true; }
  void write_figures(const std::string& directory, const std::string& name) const;
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override;

  long cycles() const { return cycles_; }
  double last_time() const { return last_time_; }   // motion time of the last state [s]
  Vector7 rms_error() const;                          // [rad]
  const Vector7& max_error() const { return max_error_; }
  const Vector7& max_tau_ext() const { return max_tau_ext_; }             // |tau_ext_hat_filtered| [N m]
  const Vector7& peak_tau_J_fraction() const { return peak_tau_J_fraction_; }   // |tau_J| / tau_max

 private:
  Reference reference_;
  MotionTime time_;
  Vector7 tau_max_;
  Vector7 squared_error_ = Vector7::Zero(), max_error_ = Vector7::Zero(), max_tau_ext_ = Vector7::Zero();
  Vector7 peak_tau_J_fraction_ = Vector7::Zero();
  long cycles_ = 0;
  double last_time_ = 0.0;

  // The figures' record (keep_figures).
  struct FigureSample {
    double t;
    Vector7 q, q_ref, tau_J;
    Vector3 tcp;   // O_T_EE's origin [m]
  };
  void keep_limit_use(const rt::RobotState& state);
  bool keep_figures_ = false;
  JointLimits limits_;
  std::vector<FigureSample> figure_samples_;
  // Peak use of each limit, a fraction of it: the position of half the range from its middle;
  // acceleration and jerk as backward differences of dq; torque rate of the commanded tau_J_d;
  // power: joint_power(tau_J, dq) against power_max.
  Vector7 position_use_ = Vector7::Zero(), velocity_use_ = Vector7::Zero(), acceleration_use_ = Vector7::Zero(),
          jerk_use_ = Vector7::Zero(), torque_use_ = Vector7::Zero(), torque_rate_use_ = Vector7::Zero();
  double power_use_ = 0.0;
  std::optional<rt::RobotState> previous_;
  std::optional<Vector7> previous_ddq_;
};

// The scenario's own trajectory from the pose the run starts in: what its built-in controller tracks.
TrackingObserver::Reference scenario_reference(const rt::Scenario& scenario, const rt::Emulator& emulator);

// A scene's task: the medical metrics (docs/medical.md). `status`: what the built-in medical
// controller found (may be null).
class MedicalObserver : public Observer {
 public:
  MedicalObserver(const Run& run, std::shared_ptr<const rt::MedicalStatus> status)
      : recorder_(run.scenario(), run.emulator(), std::move(status)), time_(run.emulator()) {}
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override { recorder_.add(state, time_.of(state)); }
  const rt::MedicalRecorder& recorder() const { return recorder_; }

 private:
  rt::MedicalRecorder recorder_;
  MotionTime time_;
};

// Progress of the run in simulated seconds, every 100 ms of robot time.
class ProgressObserver : public Observer {
 public:
  ProgressObserver(Progress progress, std::string stage, double duration, const rt::Emulator& emulator)
      : progress_(std::move(progress)), stage_(std::move(stage)), duration_(duration), time_(emulator) {}
  void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override {
    if (state.time.toMSec() % 100 == 0) report(progress_, stage_, time_.of(state), duration_);
  }

 private:
  Progress progress_;
  std::string stage_;
  double duration_;
  MotionTime time_;
};

}  // namespace csp::run
