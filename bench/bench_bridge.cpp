// csp_bridge_bench: the LCM bridge's figures (docs/bridge.md): lockstep cycles per second and
// state -> command round trip with the example controller in another process, over loopback
// UDP multicast, on both clocks; and the LCM log write rate.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "bridge_support.hpp"
#include "csp/bridge/serve.hpp"

namespace {

using namespace std::chrono_literals;

// CPU time [s] of this process (RUSAGE_SELF) or of its ended children (RUSAGE_CHILDREN).
double cpu_seconds(int who) {
  rusage usage{};
  getrusage(who, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

void run_session(const char* title, csp::rt::Clock clock, double seconds, int port_offset) {
  const std::string url = csp::test::unique_lcm_url(port_offset);
  csp::bridge::ServeOptions options;
  options.clock = clock;
  options.duration = seconds + 0.2;
  options.lcm_url = url;
  options.wait_for_controller = clock == csp::rt::Clock::kLockstep;
  options.quiet = true;
  csp::test::Process controller({CSP_LCM_FLOAT, "--lcm-url", url, "--duration", std::to_string(seconds)},
                                csp::test::temp_path("bench-controller.out"));
  const double self_cpu = cpu_seconds(RUSAGE_SELF), children_cpu = cpu_seconds(RUSAGE_CHILDREN);
  const csp::rt::Scenario scenario = csp::rt::load_scenario(csp::rt::default_scenario_path());
  csp::rt::Emulator robot(scenario.emulator);
  const csp::bridge::ServeReport r = csp::bridge::serve(robot, scenario, options);
  const int exit_code = controller.wait(10s);
  std::printf("%s: %llu cycles in %.3f s; session %llu cycles in %.3f s = %.0f cycles/s; lost commands %llu; overruns %llu\n",
              title, static_cast<unsigned long long>(r.timing.cycles), r.timing.wall_seconds,
              static_cast<unsigned long long>(r.emulator.motion_cycles), r.motion_wall_seconds,
              static_cast<double>(r.emulator.motion_cycles) / r.motion_wall_seconds,
              static_cast<unsigned long long>(r.emulator.lost_commands), static_cast<unsigned long long>(r.timing.overruns));
  std::printf("  round trip state -> command [us]: p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f (%zu)\n", r.timing.round_trip_us.p50,
              r.timing.round_trip_us.p99, r.timing.round_trip_us.p999, r.timing.round_trip_us.max, r.timing.round_trip_us.count);
  std::printf("  CPU: server %.3f s, controller process %.3f s (exit code %d)\n", cpu_seconds(RUSAGE_SELF) - self_cpu,
              cpu_seconds(RUSAGE_CHILDREN) - children_cpu, exit_code);
}

void log_write_rate(int count) {
  const std::string path = csp::test::temp_path("bench.lcmlog");
  csp::rt::Emulator emulator(csp::rt::load_scenario(csp::rt::default_scenario_path()).emulator);
  const std::vector<uint8_t> bytes = csp::bridge::encode(csp::bridge::to_message(emulator.state(), 0, false));
  const double cpu = cpu_seconds(RUSAGE_SELF);
  const auto start = std::chrono::steady_clock::now();
  {
    csp::bridge::LogWriter log(path);
    for (int i = 0; i < count; ++i) log.write("CSP_STATE", bytes, i);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double megabytes = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  std::printf("log write: %d state messages (%zu bytes each) in %.3f s (CPU %.3f s) = %.0f messages/s, %.0f MB/s\n", count,
              bytes.size(), seconds, cpu_seconds(RUSAGE_SELF) - cpu, count / seconds, megabytes / seconds);
  std::filesystem::remove(path);
}

}  // namespace

int main() {
  run_session("lockstep, csp_lcm_float process", csp::rt::Clock::kLockstep, 10.0, 4);
  run_session("real time, csp_lcm_float process", csp::rt::Clock::kRealtime, 10.0, 5);
  log_write_rate(200000);
  return 0;
}
