#include "csp/run/can_source.hpp"

namespace csp::run {

void CanBusSource::drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
                         const std::atomic<bool>& stop) {
  can::CanServeOptions options = options_;
  options.stop = &stop;
  options.after_cycle = after_cycle;
  report_ = can::serve(robot, scenario, options);
}

}  // namespace csp::run
