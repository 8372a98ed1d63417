// `csp can serve` as a run's command source (run.hpp, sources.hpp): the seven drives on SocketCAN
// (can/serve.hpp). Apart from sources.hpp so that `csp emulate` builds without the CAN bus.
#pragma once

#include "csp/can/serve.hpp"
#include "csp/run/run.hpp"

namespace csp::run {

class CanBusSource : public CommandSource {
 public:
  explicit CanBusSource(can::CanServeOptions options) : options_(std::move(options)) {}
  void drive(const rt::Scenario& scenario, rt::Emulator& robot, const rt::CycleObserver& after_cycle,
             const std::atomic<bool>& stop) override;
  const can::CanServeReport& report() const { return report_; }

 private:
  can::CanServeOptions options_;
  can::CanServeReport report_;
};

}  // namespace csp::run
