// `csp fci` as a run's command source (run.hpp, sources.hpp): the robot on the network for an
// unmodified libfranka (fci/serve.hpp). Apart from sources.hpp so that `csp emulate` builds without it.
#pragma once

#include "csp/fci/serve.hpp"
#include "csp/run/run.hpp"

namespace csp::run {

class FciSource : public CommandSource {
 public:
  explicit FciSource(fci::FciServeOptions options) : options_(std::move(options)) {}
  void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
             const std::atomic<bool>& stop) override;
  const fci::FciServeReport& report() const { return report_; }

 private:
  fci::FciServeOptions options_;
  fci::FciServeReport report_;
};

}  // namespace csp::run
