#include "csp/bridge/replay.hpp"

#include <time.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/lcm_url.hpp"
#include "csp/bridge/server.hpp"

namespace csp::bridge {

namespace {

// The states a recording may miss in a row (an hour of cycles, re-simulated in about a minute).
constexpr int64_t kMaxMissedStates = 3'600'000;

bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() >= tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

// The prefix of the first channel named ...CSP_STATE, or null.
std::optional<std::string> first_state_prefix(const std::vector<std::string>& channels) {
  static const std::string kState = "CSP_STATE";
  for (const std::string& channel : channels)
    if (ends_with(channel, kState)) return channel.substr(0, channel.size() - kState.size());
  return std::nullopt;
}

std::string damage_of(const std::string& log_path) {
  LogReader log(log_path);
  while (log.next()) {
  }
  return log.damage_summary();
}

}  // namespace

Recording::Recording(const std::string& path, const std::string& scenario_path) : log_path(path) {
  const LogOutline contents = outline(log_path);
  const std::vector<scenario_t>& records = contents.scenario_records;
  std::optional<std::string> prefix;
  if (!records.empty()) prefix = records.front().channel_prefix;
  if (!scenario_path.empty()) {
    scenario = rt::load_scenario(scenario_path);
    scenario_origin = scenario_path + " (--scenario)" + (records.empty() ? "" : ", not the log's own record");
    if (records.empty()) {
      missing = "no CSP_SCENARIO record";
      prefix = first_state_prefix(contents.channels);
    }
  } else if (!records.empty()) {
    try {
      scenario = scenario_from_message(records.front());
    } catch (const std::exception& e) {
      throw std::runtime_error(log_path + ": " + e.what());
    }
    scenario_origin = "the log's CSP_SCENARIO record (" + records.front().path + ")";
  } else {
    const std::string damage = damage_of(log_path);
    throw std::runtime_error(log_path + ": no CSP_SCENARIO record (not a recording of csp serve or csp emulate --lcm-log, or one " +
                             "that ended before the server republished it): give the scenario the robot ran with --scenario FILE" +
                             (damage.empty() ? "" : "; " + damage));
  }
  if (!prefix) throw std::runtime_error(log_path + ": no robot state (no channel named ...CSP_STATE)");
  if (records.size() > 1) scenario_origin += "; the log holds " + std::to_string(records.size()) + " robots, this one is prefix `" + *prefix + "`";
  channels = Channels(*prefix);
  has_config_replies = std::find(contents.channels.begin(), contents.channels.end(), channels.config_reply) != contents.channels.end();
}

ResimulationReport resimulate(const Recording& recording, rt::Emulator& robot, const ResimulationOptions& options) {
  const std::string& log_path = recording.log_path;
  const Channels& channels = recording.channels;
  ResimulationReport report;
  report.scenario = recording.scenario_origin;
  LogReader log(log_path);
  RobotServer server(robot, channels, [](const std::string&, const std::vector<uint8_t>&) {}, [](const std::string&) {});
  StateCoverage coverage;
  std::optional<int64_t> compared;   // message id of the last state compared
  // A configuration request has no message id, and a recording of the bus may hold it before the
  // state of the cycle the server took it in (it arrived while that state was being published).
  // The server's reply names that cycle: when the log holds replies (all but csp emulate's), each
  // request waits for its reply. A request that does not decode gets no reply: it goes at once.
  std::map<int64_t, std::vector<uint8_t>> requests;   // waiting for their reply, by request_id
  const auto stopped = [&] { return options.stop && options.stop->load(); };
  const auto run_to = [&](int64_t message_id, const LogEvent& event) {
    // The cycles of the states the recording misses (before its first, in a gap) run with the
    // messages it holds: a missed command shows as a difference in the next state.
    if (message_id > server.message_id() && message_id - server.message_id() > kMaxMissedStates)
      throw std::runtime_error(log_path + ": event " + std::to_string(event.eventnum) + ": message id " + std::to_string(message_id) +
                               " after state " + std::to_string(server.message_id()) + ": more than an hour of states missing");
    while (server.message_id() < message_id && !stopped()) {
      server.step(event.timestamp);
      if (options.after_cycle) options.after_cycle(server.emulator().state(), server.last_cycle());
    }
  };
  for (const LogEvent* event = log.next(); event && !stopped(); event = log.next()) {
    if (log.events() % 1024 == 0) csp::report(options.progress, "re-simulating (MB of the log)", 1e-6 * log.offset(), 1e-6 * log.size());
    config_request_t request;
    config_reply_t reply;
    if (event->channel == channels.config && recording.has_config_replies &&
        decode_exact(event->data, event->datalen, request) == Rejection::kNone) {
      const auto* bytes = static_cast<const uint8_t*>(event->data);
      requests[request.request_id].assign(bytes, bytes + event->datalen);
    } else if (event->channel == channels.config_reply && decode_exact(event->data, event->datalen, reply) == Rejection::kNone &&
               requests.count(reply.request_id) > 0) {
      const std::vector<uint8_t> bytes = std::move(requests[reply.request_id]);
      requests.erase(reply.request_id);
      run_to(reply.message_id, *event);
      server.receive(channels.config, bytes.data(), static_cast<int>(bytes.size()), event->timestamp);
      ++report.messages;
    } else if (event->channel == channels.command || event->channel == channels.config) {
      server.receive(event->channel, event->data, event->datalen, event->timestamp);
      ++report.messages;
    } else if (event->channel == channels.state) {
      robot_state_t recorded;
      if (const std::string refused = read_state_event(*event, recorded); !refused.empty())
        throw std::runtime_error(log_path + ": " + refused + "; `csp log export` writes the other states as CSV");
      // The message id is the robot's time: a state that says otherwise is not one of this run (and
      // its id must not make the robot run to it).
      if (recorded.message_id != recorded.time)
        throw std::runtime_error(log_path + ": event " + std::to_string(event->eventnum) + ": a state with message id " +
                                 std::to_string(recorded.message_id) + " and time " + std::to_string(recorded.time) +
                                 " ms: not a state of a CSP robot");
      if (compared && recorded.message_id == *compared) continue;   // republished while the robot waited (lcm-logger records it)
      coverage.add(recorded.message_id);
      if (recorded.message_id < server.message_id()) break;         // a new run of the server: the robot cannot go back
      run_to(recorded.message_id, *event);
      if (server.message_id() != recorded.message_id) break;   // stopped on the way
      compared = recorded.message_id;
      std::string field;
      const double difference = state_difference(recorded, server.state_message(recorded.utime), field);
      ++report.states;
      if (field.empty()) continue;
      ++report.differing_states;
      report.max_difference = std::max(report.max_difference, difference);
      if (report.first_difference.empty()) report.first_difference = "time " + std::to_string(recorded.time) + " ms: " + field;
    }
  }
  if (report.states == 0 && !stopped())
    throw std::runtime_error(log_path + ": no robot state on " + channels.state + (log.damage().empty() ? "" : " (" + log.damage_summary() + ")"));
  report.missing = recording.missing;
  if (!coverage.missing().empty()) report.missing += (report.missing.empty() ? "" : "; ") + coverage.missing();
  report.damage = log.damage_summary();
  return report;
}

ResimulationReport resimulate(const std::string& log_path, const std::string& scenario_path, const Progress& progress) {
  const Recording recording(log_path, scenario_path);
  rt::Emulator robot(recording.scenario.emulator);
  ResimulationOptions options;
  options.progress = progress;
  return resimulate(recording, robot, options);
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
    if (log.events() % 256 == 0) csp::report(options.progress, "publishing (MB of the log)", 1e-6 * log.offset(), 1e-6 * log.size());
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
