#include "cli_options.hpp"

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "csp/dynamics/arrays.hpp"
#include "csp/io/joint_log.hpp"   // output_file_problem, quote_input

namespace csp::cli {

std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& name) {
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    char* stop = nullptr;
    const double value = std::strtod(item.c_str(), &stop);
    if (item.empty() || stop != item.c_str() + item.size() || !std::isfinite(value))
      throw UsageError(name + ": " + quote_input(item) + " is not a finite number (expected " + std::to_string(count) +
                       " comma-separated numbers)");
    values.push_back(value);
    start = end + 1;
  }
  if (values.size() != count)
    throw UsageError(name + ": expected " + std::to_string(count) + " comma-separated numbers, got " +
                     std::to_string(values.size()));
  return values;
}

Vector7 parse_joint_vector(const std::string& text, const std::string& name) {
  const auto v = parse_numbers(text, kNumJoints, name);
  return from_data<Vector7>(v.data());   // parse_numbers checked the count
}

Vector3 parse_vector3(const std::string& text, const std::string& name) {
  const auto v = parse_numbers(text, 3, name);
  return from_data<Vector3>(v.data());
}

void ModelArguments::add_to(CLI::App& command) {
  command.add_option("--robot", robot, "Robot file (configs/robots/*.yaml)")->capture_default_str();
  command.add_option("--inertia", inertia, "Inertial set of the robot file (default: the file's default)");
  command.add_option("--friction", friction, "Friction set of the robot file, or `none` (default: the file's)");
  command.add_option("--limits", limits, "Joint limit set of the robot file (default: the file's)");
  command.add_option("--ee", end_effector, "End effector: none (arm alone, F_T_EE = identity) or hand")
      ->capture_default_str();
  command.add_option("--load-mass", load_mass, "Load on the flange [kg] (libfranka m_load)");
  command.add_option("--load-com", load_com, "Load centre of mass in the flange frame x,y,z [m] (default 0,0,0)");
  command.add_option("--load-inertia", load_inertia,
                     "Load inertia about its CoM Ixx,Ixy,Ixz,Iyy,Iyz,Izz [kg m^2] (default 0)");
  command.add_option("--gravity", gravity, "Gravity in the base frame gx,gy,gz [m/s^2] (default 0,0,-9.81)");
}

Model ModelArguments::build() const {
  ModelOptions options;
  options.inertia = inertia;
  options.friction = friction;
  options.joint_limits = limits;
  options.end_effector = end_effector;
  if (!load_mass.empty()) {
    RigidBodyInertia load;
    load.mass = parse_numbers(load_mass, 1, "--load-mass")[0];
    if (load.mass < 0.0) throw UsageError("--load-mass: expected a mass >= 0");
    if (!load_com.empty()) load.com = parse_vector3(load_com, "--load-com");
    if (!load_inertia.empty()) {
      const auto v = parse_numbers(load_inertia, 6, "--load-inertia");
      load.inertia << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
      if (load.mass > 0.0 && !is_physical_inertia(load.inertia) && !load.inertia.isZero())
        throw UsageError("--load-inertia: expected a positive-definite inertia satisfying the triangle inequality");
    }
    options.load = load;
  } else if (!load_com.empty() || !load_inertia.empty()) {
    throw UsageError("--load-com/--load-inertia: need --load-mass");
  }
  if (!gravity.empty()) options.gravity = parse_vector3(gravity, "--gravity");
  return Model(model_parameters(load_robot_config(robot), options));
}

void ScenarioArguments::add_to(CLI::App& command, const std::string& clock_help) {
  command.add_option("scenario", scenario, "Scenario file (default: configs/scenarios/default.yaml)");
  command.add_option("--clock", clock, clock_help)->check(CLI::IsMember({"lockstep", "realtime"}));
  command.add_option("--duration", duration, "Override the scenario's duration [s]");
}

std::string scenario_path(const std::string& given) {
  if (given.empty()) return rt::default_scenario_path();
  std::error_code error;
  const std::string shipped = rt::shipped_scenario_path(given);
  if (!std::filesystem::exists(given, error) && std::filesystem::is_regular_file(shipped, error))
    return shipped;
  return given;
}

rt::Scenario ScenarioArguments::load() const {
  rt::Scenario s = rt::load_scenario(scenario_path(scenario));
  if (duration) {
    if (!(*duration > 0.0) || !(*duration <= rt::kMaxDuration))
      throw UsageError("--duration: expected a positive number of seconds, at most a year (" + std::to_string(static_cast<int64_t>(rt::kMaxDuration)) + ")");
    s.duration = *duration;
  }
  if (!clock.empty()) s.clock = clock == "realtime" ? rt::Clock::kRealtime : rt::Clock::kLockstep;
  return s;
}

namespace {

std::atomic<bool> stop_requested{false};
std::string running_command = "csp";

// A path as messages show it: as given, unless absurdly long (a path is at most PATH_MAX bytes).
std::string shown(const std::string& path) { return path.size() <= 4096 ? path : quote_input(path, 256); }

}  // namespace

void set_command_name(const std::string& name) { running_command = name; }
const std::string& command_name() { return running_command; }

Outputs& Outputs::file(const std::string& option, const std::string& path) {
  if (!path.empty()) files_.push_back({option, path, ""});
  return *this;
}

Outputs& Outputs::directory(const std::string& option, const std::string& path, const std::vector<std::string>& names) {
  if (path.empty()) return *this;
  directories_.push_back({option, path, path});
  for (const std::string& name : names) files_.push_back({option + " (its " + name + ")", (std::filesystem::path(path) / name).string(), path});
  return *this;
}

Outputs& Outputs::input(const std::string& what, const std::string& path) {
  if (!path.empty()) inputs_.push_back({what, path, ""});
  return *this;
}

void Outputs::check() const {
  for (const Entry& d : directories_)
    if (const std::string problem = output_directory_problem(d.path); !problem.empty())
      throw UsageError(d.option + " " + shown(d.path) + ": " + problem);
  for (const Entry& f : files_) {
    // A file in a directory output that is yet to be made: the directory's check says it all.
    const std::string parent = std::filesystem::path(f.path).parent_path().string();
    const bool in_new_directory = std::any_of(directories_.begin(), directories_.end(), [&](const Entry& d) {
      return !std::filesystem::is_directory(d.path) && (d.path == f.directory || same_file(parent.empty() ? "." : parent, d.path));
    });
    if (in_new_directory) continue;
    if (const std::string problem = output_file_problem(f.path); !problem.empty())
      throw UsageError(f.option + " " + shown(f.path) + ": " + problem);
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    for (const Entry& in : inputs_)
      if (same_file(files_[i].path, in.path))
        throw UsageError(files_[i].option + " " + shown(files_[i].path) + ": is the input file (" + in.option +
                         "); choose another output file");
    for (std::size_t j = 0; j < i; ++j)
      if (same_file(files_[i].path, files_[j].path))
        throw UsageError(files_[i].option + " " + shown(files_[i].path) + ": the same file as " + files_[j].option +
                         "; give each output a file of its own");
    for (const Entry& d : directories_)
      if (files_[i].directory != d.path && same_file(files_[i].path, d.path))
        throw UsageError(files_[i].option + " " + shown(files_[i].path) + ": the directory of " + d.option +
                         "; give each output a path of its own");
  }
}

std::atomic<bool>& stop_on_signals() {
  stop_requested = false;
  std::signal(SIGINT, [](int) { stop_requested = true; });
  std::signal(SIGTERM, [](int) { stop_requested = true; });
  return stop_requested;
}

namespace {

void print_percentiles(const std::string& name, const rt::Percentiles& p, const char* samples) {
  if (p.count == 0) return;
  std::printf("  %-34s p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f us (%zu %s)\n", name.c_str(), p.p50, p.p99, p.p999, p.max,
              p.count, samples);
}

}  // namespace

void print_timing(const rt::TimingReport& timing, const char* round_trip) {
  std::printf("  %s clock: %llu cycles in %.3f s of wall time (%.0f cycles/s)\n", rt::clock_name(timing.clock),
              static_cast<unsigned long long>(timing.cycles), timing.wall_seconds,
              timing.wall_seconds > 0.0 ? static_cast<double>(timing.cycles) / timing.wall_seconds : 0.0);
  print_percentiles(round_trip, timing.round_trip_us, "commands");
  if (timing.clock == rt::Clock::kRealtime) {
    std::printf("  real-time scheduling (SCHED_FIFO) %s, memory locked (mlockall) %s\n",
                timing.realtime.scheduling ? "obtained" : "NOT obtained", timing.realtime.memory_locked ? "yes" : "NO");
    print_percentiles("wake-up latency after deadline", timing.wakeup_latency_us, "cycles");
    std::printf("  overruns %llu, missed deadlines %llu\n", static_cast<unsigned long long>(timing.overruns),
                static_cast<unsigned long long>(timing.missed_deadlines));
  }
  for (const std::string& warning : timing.warnings) std::printf("  warning: %s\n", warning.c_str());
}

std::optional<int> print_early_end(const std::string& observer_failure, bool stopped, double robot_time, int signal_status) {
  if (!observer_failure.empty()) {
    std::printf("  STOPPED at t = %.3f s: a log could not be written (the error is on stderr)\n", robot_time);
    std::fflush(stdout);
    std::fprintf(stderr, "csp %s: %s\n", command_name().c_str(), observer_failure.c_str());
    return 2;
  }
  if (!stopped) return std::nullopt;
  std::printf("  STOPPED at t = %.3f s by a signal (Ctrl-C or SIGTERM)\n", robot_time);
  return signal_status;
}

}  // namespace csp::cli
