// The medical metrics of a run on a scene's task (docs/medical.md), recorded cycle by cycle from
// the published RobotState (what the robot believes: O_T_EE, O_F_ext_hat_K) and the plant's true
// forces (Emulator::contact(): the scene's contacts and the tissue elements'), and the figures
// `csp emulate --report DIR` writes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "csp/rt/medical_controllers.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::rt {

struct MedicalMetric {
  std::string name;
  double value = 0.0;
  std::string unit;
};

class MedicalRecorder {
 public:
  // The scenario must have a scene; `emulator` runs it (and outlives the recorder); `status` is
  // the built-in controller's (may be null).
  MedicalRecorder(const Scenario& scenario, const Emulator& emulator, std::shared_ptr<const MedicalStatus> status);

  // One cycle at motion time t [s].
  void add(const RobotState& state, double t);

  // The task's metrics: ultrasound (force RMS error, contact losses, path error, skin indentation), RCM (deviation,
  // trocar force), drilling (thrust, breakthrough time, overshoot); each with the error of the
  // robot's estimated contact force against the true one.
  std::vector<MedicalMetric> metrics() const;
  // force.svg (true and estimated force along the tool axis), path.svg and penetration.svg.
  void write_figures(const std::string& directory) const;

 private:
  struct Sample {
    double t;
    Vector3 true_force;        // the tool pushes the tissue with it (base frame) [N]
    Vector3 estimated_force;   // O_F_ext_hat_K's force [N]
    Vector3 tcp, axis;         // O_T_EE's origin and z axis
    double depth;              // along the task's axis: below the skin line, burr entry, trocar [m]
    double penetration;        // the scene contact's deepest [m]
  };
  double axial(const Vector3& force, const Sample& s) const;   // along the task's push direction
  double path_error(const Sample& s) const;                    // [m] from the task's path

  const Emulator& emulator_;
  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const BoneUnderBurr> bone_;
  std::shared_ptr<const MedicalStatus> status_;
  MedicalControllerSpec controller_;
  std::vector<Sample> samples_;
};

}  // namespace csp::rt
