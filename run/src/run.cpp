#include "csp/run/run.hpp"

#include <exception>

namespace csp::run {

RunResult Run::run(CommandSource& source, std::atomic<bool>* stop) {
  RunResult result;
  std::atomic<bool> own_stop = false;
  std::atomic<bool>& halt = stop ? *stop : own_stop;
  std::vector<Observer*> active = observers_;
  const rt::CycleObserver after_cycle = [&](const rt::RobotState& state, const rt::CycleInfo& cycle) {
    for (Observer*& observer : active) {
      if (!observer) continue;
      try {
        observer->on_cycle(state, cycle);
      } catch (const std::exception& e) {
        if (result.observer_failure.empty()) result.observer_failure = e.what();
        observer = nullptr;   // not called again: a log that failed stays as it was left
        halt = true;
      }
    }
  };
  source.drive(scenario_, emulator_, after_cycle, halt);
  result.stopped = halt && result.observer_failure.empty();
  return result;
}

}  // namespace csp::run
