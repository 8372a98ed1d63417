#include "csp/run/fci_source.hpp"

namespace csp::run {

void FciSource::drive(const rt::Scenario&, rt::Emulator& robot, const rt::CycleObserver& after_cycle, const std::atomic<bool>& stop) {
  fci::FciServeOptions options = options_;
  options.stop = &stop;
  options.after_cycle = after_cycle;
  report_ = fci::serve_fci(robot, options);
}

}  // namespace csp::run
