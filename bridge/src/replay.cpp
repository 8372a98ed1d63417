#include "csp/bridge/replay.hpp"

#include <time.h>

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <memory>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/lcm_url.hpp"
#include "csp/bridge/server.hpp"

namespace csp::bridge {

ResimulationReport resimulate(const std::string& log_path) {
  LogReader log(log_path);
  // Both come from the scenario record, the log's first event.
  std::unique_ptr<RobotServer> server;
  std::unique_ptr<Channels> channels;
  ResimulationReport report;
  bool first_state = true;
  for (const LogEvent* event = log.next(); event; event = log.next()) {
    if (!server) {
      // The scenario record comes first: it names the channels and rebuilds the emulator.
      scenario_t record;
      if (event->channel.size() < 12 || event->channel.compare(event->channel.size() - 12, 12, "CSP_SCENARIO") != 0 ||
          decode_exact(event->data, event->datalen, record) != Rejection::kNone)
        throw std::runtime_error(log_path + ": the first event is not a CSP_SCENARIO record (not a log written by csp serve or csp emulate --lcm-log)" +
                                 (log.damage().empty() ? "" : "; " + log.damage_summary()));
      rt::Scenario scenario;
      try {
        scenario = scenario_from_message(record);
      } catch (const std::exception& e) {
        throw std::runtime_error(log_path + ": event " + std::to_string(event->eventnum) + ": " + e.what());
      }
      channels = std::make_unique<Channels>(record.channel_prefix);
      server = std::make_unique<RobotServer>(scenario.emulator, *channels, [](const std::string&, const std::vector<uint8_t>&) {},
                                             [](const std::string&) {});
      continue;
    }
    if (event->channel == channels->command || event->channel == channels->config) {
      server->receive(event->channel, event->data, event->datalen, event->timestamp);
      ++report.messages;
    } else if (event->channel == channels->state) {
      robot_state_t recorded;
      if (decode_exact(event->data, event->datalen, recorded) != Rejection::kNone)
        throw std::runtime_error(log_path + ": event " + std::to_string(event->eventnum) + " on " + event->channel + " is not a robot_state_t");
      if (!first_state) server->step(event->timestamp);   // each recorded state after the first ends a cycle
      first_state = false;
      std::string field;
      const double difference = state_difference(recorded, server->state_message(recorded.utime), field);
      ++report.states;
      if (field.empty()) continue;
      ++report.differing_states;
      report.max_difference = std::max(report.max_difference, difference);
      if (report.first_difference.empty()) report.first_difference = "time " + std::to_string(recorded.time) + " ms: " + field;
    }
  }
  if (!server) throw std::runtime_error(log_path + ": empty log" + (log.damage().empty() ? "" : " (" + log.damage_summary() + ")"));
  report.damage = log.damage_summary();
  return report;
}

PlaybackReport play_back(const std::string& log_path, const PlaybackOptions& options) {
  if (!(options.speed == 0.0 || (options.speed >= kMinPlaybackSpeed && options.speed <= kMaxPlaybackSpeed)))
    throw std::invalid_argument("speed: expected 0 (as fast as possible) or a factor from 0.001 to 1e6");
  if (!(options.max_gap > 0.0) || !std::isfinite(options.max_gap))
    throw std::invalid_argument("max gap: expected a positive number of seconds");
  LogReader log(log_path);
  lcm::LCM lcm(checked_lcm_url(options.lcm_url));
  if (!lcm.good()) throw std::runtime_error("cannot open LCM at `" + options.lcm_url + "`");
  PlaybackReport report;
  // The schedule advances by each gap between consecutive timestamps (in doubles: a corrupted
  // timestamp such as INT64_MIN must not overflow), so one wrong timestamp costs no wait.
  double schedule_s = 0.0;
  int64_t previous_timestamp = 0;
  timespec start{};
  clock_gettime(CLOCK_MONOTONIC, &start);
  for (const LogEvent* event = log.next(); event; event = log.next()) {
    if (options.stop && options.stop->load()) break;
    if (report.published > 0 && options.speed > 0.0) {
      const double gap_s = (static_cast<double>(event->timestamp) - static_cast<double>(previous_timestamp)) * 1e-6;
      if (gap_s < 0.0 || gap_s > options.max_gap) ++report.timestamp_jumps;
      else schedule_s += gap_s / options.speed;
      // Bounded: at most (events x max_gap / kMinPlaybackSpeed) seconds, far inside time_t.
      const auto whole = static_cast<time_t>(schedule_s);
      timespec at = start;
      at.tv_sec += whole;
      at.tv_nsec += static_cast<long>((schedule_s - static_cast<double>(whole)) * 1e9);
      if (at.tv_nsec >= 1'000'000'000) {
        at.tv_nsec -= 1'000'000'000;
        ++at.tv_sec;
      }
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
        if (options.stop && options.stop->load()) break;
      }
    }
    previous_timestamp = event->timestamp;
    lcm.publish(event->channel, event->data, static_cast<unsigned>(event->datalen));
    ++report.published;
  }
  report.damage = log.damage_summary();
  return report;
}

}  // namespace csp::bridge
