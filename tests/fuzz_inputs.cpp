// csp_fuzz: generated and mutated inputs for every input class CSP reads, each run classified as
// accepted, rejected with one clear line, unclear (another exception type, a message of several
// lines or not naming its source, or an accepted input that yields non-finite numbers), crash or
// hang. In-process classes run in this process (a crash kills it: the input being run is saved
// first to fuzz-<class>.input); the CLI class runs the `csp` program.
//
//   csp_fuzz --class robot_yaml|scenario_yaml|csv_log|lcm_log|lcm_messages|cli|all --budget N [--seed S]
//
// Exit code 0 when every input was accepted or rejected clearly; 1 otherwise (the first inputs of
// each bad kind are printed).
#include <fcntl.h>
#include <sys/resource.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <variant>
#include <vector>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/bridge/server.hpp"
#include "csp/dynamics/algorithms.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/robot_config.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/csv_log.hpp"
#include "csp/rt/scenario.hpp"

extern char** environ;

namespace csp::fuzz {
namespace {

enum class Outcome { kAccepted, kRejected, kUnclear, kCrash, kHang };
const char* outcome_name(Outcome o) {
  switch (o) {
    case Outcome::kAccepted: return "accepted";
    case Outcome::kRejected: return "rejected";
    case Outcome::kUnclear: return "unclear";
    case Outcome::kCrash: return "crash";
    case Outcome::kHang: return "hang";
  }
  return "?";
}

struct Verdict {
  Outcome outcome = Outcome::kAccepted;
  std::string detail;   // the message, or why it is unclear
};

// A rejection is clear when it is one line naming where the problem is (`source`), and says what
// is wrong (yaml-cpp's "bad file", its depth guard's message, does not).
Verdict rejection(const std::string& message, const std::string& source) {
  if (message.find('\n') != std::string::npos) return {Outcome::kUnclear, "several lines: " + message};
  if (message.find("bad file") != std::string::npos) return {Outcome::kUnclear, "does not say what is wrong: " + message};
  if (!source.empty() && message.find(source) == std::string::npos) return {Outcome::kUnclear, "does not name " + source + ": " + message};
  return {Outcome::kRejected, message};
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// ---------------------------------------------------------------------------------------------
// Mutations

class Mutator {
 public:
  explicit Mutator(uint64_t seed) : rng_(seed) {}
  std::size_t below(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }
  template <typename T>
  const T& pick(const std::vector<T>& items) { return items[below(items.size())]; }

  // Text (YAML, CSV): 1-3 edits of lines, numbers, keys and characters.
  std::string text(std::string s) {
    const std::size_t edits = 1 + below(3);
    for (std::size_t e = 0; e < edits && !s.empty(); ++e) {
      std::vector<std::string> lines = split_lines(s);
      const std::size_t i = below(lines.size());
      switch (below(8)) {
        case 0: lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(i)); break;
        case 1: lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]); break;
        case 2: std::swap(lines[i], lines[below(lines.size())]); break;
        case 3: lines[i] = replace_number(lines[i]); break;
        case 4: lines[i] = replace_number(lines[i]); break;
        case 5: if (!lines[i].empty()) lines[i][below(lines[i].size())] = pick(kCharacters); break;
        case 6: lines[i].insert(below(lines[i].size() + 1), pick(kFragments)); break;
        case 7: lines.resize(i); break;   // cut short
      }
      s.clear();
      for (const std::string& line : lines) s += line + '\n';
    }
    return s;
  }

  // Binary (LCM logs and messages): bit flips, extreme words, cuts, repeats.
  std::vector<uint8_t> bytes(std::vector<uint8_t> b) {
    const std::size_t edits = 1 + below(4);
    for (std::size_t e = 0; e < edits && !b.empty(); ++e) {
      const std::size_t i = below(b.size());
      switch (below(6)) {
        case 0: b[i] ^= static_cast<uint8_t>(1u << below(8)); break;
        case 1: b[i] = static_cast<uint8_t>(below(256)); break;
        case 2: {   // an extreme 4- or 8-byte word (lengths, counts, doubles)
          static const std::vector<std::vector<uint8_t>> words = {
              {0x7f, 0xff, 0xff, 0xff}, {0x80, 0, 0, 0}, {0xff, 0xff, 0xff, 0xff}, {0, 0, 0, 0},
              {0x7f, 0xf0, 0, 0, 0, 0, 0, 0} /* inf */, {0x7f, 0xf8, 0, 0, 0, 0, 0, 0} /* NaN */,
              {0x7e, 0x37, 0xe4, 0x3c, 0x88, 0x00, 0x75, 0x9c} /* 1e300 */};
          const std::vector<uint8_t>& w = pick(words);
          for (std::size_t k = 0; k < w.size() && i + k < b.size(); ++k) b[i + k] = w[k];
          break;
        }
        case 3: b.resize(i); break;
        case 4: b.insert(b.begin() + static_cast<std::ptrdiff_t>(i), b.begin(), b.begin() + static_cast<std::ptrdiff_t>(std::min(b.size() - i, below(64) + 1))); break;
        case 5: b.erase(b.begin() + static_cast<std::ptrdiff_t>(i), b.begin() + static_cast<std::ptrdiff_t>(std::min(b.size(), i + below(16) + 1))); break;
      }
    }
    return b;
  }

  // YAML files: one time in 16 a structural edit a line edit would not make (anchors and aliases,
  // an alias bomb, deep nesting, a big list under an unknown key), else text().
  std::string yaml(std::string s) {
    if (below(16) != 0) return text(std::move(s));
    switch (below(6)) {
      case 0: {   // an alias bomb: `levels` lists of `width` aliases each to the list before
        const std::size_t levels = 1 + below(9), width = 2 + below(9);
        std::string list = "x";
        for (std::size_t l = 0; l < levels; ++l) {
          std::string items;
          for (std::size_t i = 0; i < width; ++i) items += (i ? ", " : "") + list;
          s += "bomb" + std::to_string(l) + ": &b" + std::to_string(l) + " [" + items + "]\n";
          list = "*b" + std::to_string(l);
        }
        return s;
      }
      case 1: {   // an anchor on one value and its alias in place of another (maybe before the anchor)
        std::vector<std::string> lines = split_lines(s);
        std::vector<std::size_t> values;
        for (std::size_t i = 0; i < lines.size(); ++i)
          if (const std::size_t at = lines[i].find(": "); at != std::string::npos && lines[i].find('#') > at) values.push_back(i);
        if (values.size() < 2) return s;
        std::string& anchored = lines[pick(values)];
        anchored.insert(anchored.find(": ") + 2, "&v ");
        std::string& aliased = lines[pick(values)];
        aliased = aliased.substr(0, aliased.find(": ") + 2) + "*v";
        s.clear();
        for (const std::string& line : lines) s += line + '\n';
        return s;
      }
      case 2: return s + pick(std::vector<std::string>{"cycle: &c [*c]\n", "cycle: &c {a: *c}\n", "cycle: &c [[*c]]\n"});
      case 3: {   // deep flow nesting (yaml-cpp's own guard is near 500 levels)
        const std::size_t depth = 1 + below(3000);
        const bool maps = below(2) == 0;
        std::string open, close;
        for (std::size_t d = 0; d < depth; ++d) open += maps ? "{a: " : "[", close += maps ? "}" : "]";
        return s + "deep: " + open + "1" + close + "\n";
      }
      case 4: {   // deep block maps: one key per line, each indented one more
        const std::size_t depth = 1 + below(1500);
        s += "deep:\n";
        for (std::size_t d = 1; d <= depth; ++d) s += std::string(d, ' ') + "k:\n";
        return s + std::string(depth + 1, ' ') + "v: 1\n";
      }
      default: {   // a list under an unknown key: small, beyond 1 MB, or the issue's 10 MB (1.4 GB once parsed)
        const std::size_t items = pick(std::vector<std::size_t>{10, 1000, 300'000, 2'600'000});
        std::string list = "- 1\n";
        while (list.size() < 4 * items) list += list;
        return s + "big:\n" + list.substr(0, 4 * items);
      }
    }
  }

  std::mt19937_64& rng() { return rng_; }

 private:
  static std::vector<std::string> split_lines(const std::string& s) {
    std::vector<std::string> lines;
    std::stringstream in(s);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    if (lines.empty()) lines.emplace_back();
    return lines;
  }

  std::string replace_number(const std::string& line) {
    std::vector<std::pair<std::size_t, std::size_t>> numbers;   // [begin, end)
    for (std::size_t i = 0; i < line.size();) {
      if (std::isdigit(static_cast<unsigned char>(line[i])) || (line[i] == '-' && i + 1 < line.size() && std::isdigit(static_cast<unsigned char>(line[i + 1])))) {
        std::size_t j = i + 1;
        while (j < line.size() && (std::isdigit(static_cast<unsigned char>(line[j])) || std::strchr(".eE+-", line[j]))) ++j;
        numbers.emplace_back(i, j);
        i = j;
      } else {
        ++i;
      }
    }
    if (numbers.empty()) return line;
    const auto [begin, end] = pick(numbers);
    return line.substr(0, begin) + pick(kNumbers) + line.substr(end);
  }

  inline static const std::vector<std::string> kNumbers = {"0", "-0", "-1", "1e308", "-1e308", "1e-320", "nan", ".nan", "inf",
                                                           ".inf", "1e18", "9223372036854775808", "3.5", "", "1e200", "0x10", "true"};
  inline static const std::vector<char> kCharacters = {' ', ':', '-', '[', ']', '{', '}', ',', '\t', '#', '"', 'x', '\0'};
  inline static const std::vector<std::string> kFragments = {": ", " - ", "[", "]", "{a: 1}", "&a ", "*a", "!!binary ", "---\n",
                                                             "\t", "key: value", "~", "''", "1e999"};
  std::mt19937_64 rng_;
};

// ---------------------------------------------------------------------------------------------
// The classes

struct Class {
  std::string name;
  std::function<std::string(Mutator&)> generate;          // one input (as bytes in a string)
  std::function<Verdict(const std::string&)> run;          // in-process; empty for the CLI class
};

std::string temp_dir() {
  static const std::string dir = [] {
    const std::filesystem::path p = std::filesystem::temp_directory_path() / ("csp-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(p);
    return p.string();
  }();
  return dir;
}

bool finite(const rt::RobotState& s) {
  for (double v : s.q) if (!std::isfinite(v)) return false;
  for (double v : s.dq) if (!std::isfinite(v)) return false;
  for (double v : s.tau_J) if (!std::isfinite(v)) return false;
  return true;
}

// A YAML input that takes the process's peak memory past 1 GB is unclear however it ends: a 10 MB
// list under an unknown key took 2.3 GB before it was refused.
Verdict within_memory(const std::function<Verdict()>& run) {
  constexpr long kMaxPeakKb = 1L << 20;
  const auto peak_kb = [] {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
  };
  const long before = peak_kb();
  const Verdict verdict = run();
  const long after = peak_kb();
  if (after > kMaxPeakKb && after > before)
    return {Outcome::kUnclear, "the peak memory grew to " + std::to_string(after >> 10) + " MB (" + verdict.detail + ")"};
  return verdict;
}

Class robot_yaml() {
  const std::vector<std::string> bases = {read_text(std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml"),
                                          read_text(std::string(CSP_SOURCE_DIR) + "/configs/robots/fr3.yaml")};
  return {"robot_yaml", [bases](Mutator& m) { return m.yaml(m.pick(bases)); },
          [](const std::string& input) { return within_memory([&]() -> Verdict {
            const std::string path = temp_dir() + "/robot.yaml";
            write_text(path, input);
            try {
              const Model model(model_parameters(load_robot_config(path), ModelOptions{}));
              Data data;
              Vector7 g;
              gravity_torque(model, data, Vector7::Constant(0.3), g);
              if (!g.allFinite()) return {Outcome::kUnclear, "accepted, but the gravity torque is not finite"};
              return {};
            } catch (const ConfigError& e) {
              return rejection(e.what(), path);
            } catch (const std::exception& e) {
              return {Outcome::kUnclear, std::string("not a ConfigError: ") + e.what()};
            }
          }); }};
}

Class scenario_yaml() {
  std::vector<std::string> bases;
  // The shipped scenarios, their robot files named by absolute path so that the mutants can live
  // in a temporary folder (never beside the shipped files, where other tests list them).
  const std::string robots = std::string(CSP_SOURCE_DIR) + "/configs/robots/";
  for (const char* name : {"default", "fr3_float", "lossy_network"}) {
    std::string text = read_text(std::string(CSP_SOURCE_DIR) + "/configs/scenarios/" + name + ".yaml");
    for (std::size_t at = text.find("../robots/"); at != std::string::npos; at = text.find("../robots/", at))
      text.replace(at, 10, robots);
    bases.push_back(text);
  }
  return {"scenario_yaml", [bases](Mutator& m) { return m.yaml(m.pick(bases)); },
          [](const std::string& input) { return within_memory([&]() -> Verdict {
            const std::string path = temp_dir() + "/scenario.yaml";
            write_text(path, input);
            try {
              const rt::Scenario scenario = rt::load_scenario(path);
              rt::Emulator emulator(scenario.emulator);
              for (int k = 0; k < 50; ++k) emulator.step(nullptr);   // idle: the robot holds its pose
              if (!finite(emulator.state())) return {Outcome::kUnclear, "accepted, but the idle robot's state is not finite"};
              return {};
            } catch (const ConfigError& e) {
              // Errors inside the robot file it names are that file's: either file is named.
              const std::string message = e.what();
              return rejection(message, message.rfind(path, 0) == 0 ? path : "/configs/robots/");
            } catch (const std::invalid_argument& e) {   // emulator settings refused at construction
              return rejection(e.what(), "");
            } catch (const std::exception& e) {
              return {Outcome::kUnclear, std::string("not a ConfigError: ") + e.what()};
            }
          }); }};
}

// Sizes no joint log has: a column name, a field, a line of megabytes (a 10 MB column name took
// 46 s and printed a 10 MB message), and numbers a robot never reports (1e300 N m was accepted).
// One input in 16 gets one of them, so that the class keeps its run time.
std::string huge_mutation(Mutator& m, std::string text) {
  static const std::vector<std::size_t> sizes = {300, 5000, 100'000, 1'100'000};   // the last: past the 1 MiB line bound
  const std::size_t size = m.pick(sizes);
  const std::size_t header_end = text.find('\n');
  switch (m.below(4)) {
    case 0: {   // a huge column name, in place of one of the header's or added at its end
      const std::size_t at = header_end == std::string::npos ? text.size() : header_end;
      const std::string name = m.below(2) ? "x_" + std::string(size, 'a') : std::string(size, 'q');
      return text.substr(0, at) + (m.below(2) ? "," + name : "") + (m.below(2) ? "" : "," + name) + text.substr(at);
    }
    case 1: {   // a very long line among the rows
      const std::size_t at = text.find('\n', m.below(text.size() + 1));
      std::string line(size, '1');
      for (std::size_t k = 0; k < line.size(); k += 1 + m.below(40)) line[k] = ',';
      return at == std::string::npos ? text + line + '\n' : text.substr(0, at + 1) + line + '\n' + text.substr(at + 1);
    }
    case 2: {   // a huge field: a number of `size` digits
      const std::size_t at = text.find(',', header_end == std::string::npos ? 0 : header_end + m.below(text.size()));
      return at == std::string::npos ? text : text.substr(0, at + 1) + std::string(size, '7') + text.substr(at + 1);
    }
    default: {  // a huge but finite number in a field
      static const std::vector<std::string> numbers = {"1e300", "-1e300", "1e200", "1.7976931348623157e308", "1e160", "-1e20", "4e4"};
      const std::size_t at = text.find(',', header_end == std::string::npos ? 0 : header_end + m.below(text.size()));
      if (at == std::string::npos) return text;
      const std::size_t end = text.find_first_of(",\n", at + 1);
      return text.substr(0, at + 1) + m.pick(numbers) + (end == std::string::npos ? "" : text.substr(end));
    }
  }
}

// A rejection of the joint-log readers is also one of bounded length, quick: the input it quotes
// is shortened (quote_input).
constexpr std::size_t kMaxMessageBytes = 1024;
constexpr double kMaxSeconds = 10.0;   // per input; the longest take about 20 ms (1 MB read)

// An accepted joint log must be usable: what every fit computes, sums of squares of its numbers,
// stays finite (1e300 N m passed every check but overflows the first one).
std::string unusable_value(const JointLog& log) {
  for (const ColumnGroup& group : kJointLogSchema) {
    if (group.text) continue;
    std::string problem;
    std::visit(
        [&](auto member) {
          using Series = std::decay_t<decltype(log.*member)>;
          if constexpr (!std::is_same_v<typename Series::value_type, std::string>) {
            const Series& series = log.*member;
            for (std::size_t k = 0; k < series.size() && problem.empty(); ++k) {
              double squares = 0.0;
              if constexpr (std::is_same_v<typename Series::value_type, double>) squares = series[k] * series[k];
              else squares = series[k].squaredNorm();
              if (!std::isfinite(squares)) problem = "row " + std::to_string(k + 1) + ", group " + std::string(group.name);
            }
          }
        },
        group.member);
    if (!problem.empty()) return problem;
  }
  return {};
}

// Joint logs: the real Panda log's first rows, and the emulator's full column set.
Class csv_log() {
  std::vector<std::string> bases;
  {
    std::ifstream in(std::string(CSP_SHARED_DATA_DIR) + "/real/panda_exciting_traj_1.csv");
    std::string text, line;
    for (int k = 0; k < 40 && std::getline(in, line); ++k) text += line + '\n';
    bases.push_back(text);
  }
  {
    const std::string path = temp_dir() + "/emulated.csv";
    const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
    rt::Emulator emulator(scenario.emulator);
    {
      rt::CsvLog log(path);   // written out when it closes
      for (int k = 0; k < 30; ++k) {
        emulator.step(nullptr);
        log.write(emulator.state(), rt::CycleInfo{});
      }
    }
    bases.push_back(read_text(path));
  }
  return {"csv_log",
          [bases](Mutator& m) {
            std::string text = m.text(m.pick(bases));
            return m.below(16) == 0 ? huge_mutation(m, std::move(text)) : text;
          },
          [](const std::string& input) -> Verdict {
            const std::string path = temp_dir() + "/fuzz.csv";
            write_text(path, input);
            const auto start = std::chrono::steady_clock::now();
            Verdict verdict;
            try {
              const JointLog log = read_joint_log_csv(path);
              if (const std::string where = unusable_value(log); !where.empty())
                verdict = {Outcome::kUnclear, "accepted, but a value's square overflows (" + where + "): not physically plausible"};
            } catch (const JointLogError& e) {
              const std::string message = e.what();
              verdict = message.size() > kMaxMessageBytes
                            ? Verdict{Outcome::kUnclear, "a message of " + std::to_string(message.size()) + " bytes: " + message.substr(0, 200)}
                            : rejection(message, path);
            } catch (const std::exception& e) {
              verdict = {Outcome::kUnclear, std::string("not a JointLogError: ") + e.what()};
            }
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (seconds > kMaxSeconds) verdict = {Outcome::kUnclear, "slow: " + std::to_string(seconds) + " s (" + verdict.detail.substr(0, 200) + ")"};
            return verdict;
          }};
}

std::vector<uint8_t> small_csp_log() {
  const std::string path = temp_dir() + "/base.lcmlog";
  const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
  {
    bridge::EmulateLogRecorder recorder(path, scenario, emulator, builtin.mode);
    rt::LoopOptions options;
    options.max_duration = 0.03;
    options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) { recorder.record(s, c); };
    rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  }
  const std::string text = read_text(path);
  return {text.begin(), text.end()};
}

Class lcm_log() {
  const std::vector<uint8_t> base = small_csp_log();
  return {"lcm_log",
          [base](Mutator& m) {
            const std::vector<uint8_t> b = m.bytes(base);
            return std::string(b.begin(), b.end());
          },
          [](const std::string& input) -> Verdict {
            const std::string path = temp_dir() + "/fuzz.lcmlog";
            write_text(path, input);
            try {
              bridge::resimulate(path);
              return {};
            } catch (const std::runtime_error& e) {
              return rejection(e.what(), path);
            } catch (const std::exception& e) {
              return {Outcome::kUnclear, std::string("not a runtime_error: ") + e.what()};
            }
          }};
}

// A session on an in-process robot server (the transport-free half of `csp serve`): start a
// motion, then commands and configuration requests, some valid, some mutated, some with extreme
// values. The server must never throw, and the robot must never hold a non-finite state.
Class lcm_messages() {
  return {"lcm_messages",
          [](Mutator& m) {
            std::string script;   // a sequence of (channel byte, length, bytes)
            auto add = [&](char channel, const std::vector<uint8_t>& bytes) {
              script += channel;
              const auto n = static_cast<uint32_t>(bytes.size());
              script.append(reinterpret_cast<const char*>(&n), 4);
              script.append(bytes.begin(), bytes.end());
            };
            const std::vector<double> extremes = {0.0, -1.0, 1e300, -1e300, NAN, INFINITY, 1e-320, 3.0, 100.0};
            for (int k = 0; k < 40; ++k) {
              config_request_t r{};
              r.request = static_cast<int8_t>(1 + m.below(7));
              r.control_mode = static_cast<int8_t>(m.below(4));
              r.load_mass = m.pick(extremes);
              for (double& v : r.F_x_Cload) v = m.below(2) ? 0.01 : m.pick(extremes);
              for (int i = 0; i < 9; ++i) r.load_inertia[i] = i % 4 == 0 ? 0.01 : (m.below(3) ? 0.0 : m.pick(extremes));
              for (double& v : r.K_theta) v = m.below(2) ? 1000.0 : m.pick(extremes);
              for (int i = 0; i < 16; ++i) r.NE_T_EE[i] = r.EE_T_K[i] = i % 5 == 0 ? 1.0 : (m.below(4) ? 0.0 : m.pick(extremes));
              for (double* v : {r.lower_torque_thresholds_acceleration, r.upper_torque_thresholds_acceleration,
                                r.lower_torque_thresholds_nominal, r.upper_torque_thresholds_nominal})
                for (int i = 0; i < 7; ++i) v[i] = m.below(2) ? 20.0 : m.pick(extremes);
              for (double* v : {r.lower_force_thresholds_acceleration, r.upper_force_thresholds_acceleration,
                                r.lower_force_thresholds_nominal, r.upper_force_thresholds_nominal})
                for (int i = 0; i < 6; ++i) v[i] = m.below(2) ? 20.0 : m.pick(extremes);
              std::vector<uint8_t> bytes = bridge::encode(r);
              if (m.below(4) == 0) bytes = m.bytes(bytes);
              add('c', bytes);
              for (int step = 0; step < 1 + static_cast<int>(m.below(5)); ++step) {
                torque_command_t t{};
                for (double& v : t.tau_J) v = m.below(3) ? 0.0 : m.pick(extremes);
                t.message_id = -1;   // filled in at run time: answers the current state
                std::vector<uint8_t> command = bridge::encode(t);
                if (m.below(5) == 0) command = m.bytes(command);
                add('m', command);
                add('s', {});
              }
            }
            return script;
          },
          [](const std::string& script) -> Verdict {
            const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
            const bridge::Channels channels;
            rt::Emulator robot(scenario.emulator);
            bridge::RobotServer server(robot, channels, [](const std::string&, const std::vector<uint8_t>&) {},
                                       [](const std::string&) {});
            try {
              for (std::size_t at = 0; at + 5 <= script.size();) {
                const char channel = script[at];
                uint32_t n = 0;
                std::memcpy(&n, script.data() + at + 1, 4);
                std::vector<uint8_t> bytes(script.begin() + static_cast<std::ptrdiff_t>(at + 5),
                                           script.begin() + static_cast<std::ptrdiff_t>(at + 5 + n));
                at += 5 + n;
                if (channel == 's') {
                  server.step(0);
                  if (!finite(server.emulator().state()))
                    return {Outcome::kUnclear, "the robot's state became non-finite (mode " +
                                                   std::string(rt::robot_mode_name(server.emulator().state().robot_mode)) + ")"};
                } else if (channel == 'm') {
                  torque_command_t t;
                  if (bridge::decode_exact(bytes.data(), static_cast<int>(bytes.size()), t) == bridge::Rejection::kNone && t.message_id == -1) {
                    t.message_id = server.message_id();
                    bytes = bridge::encode(t);
                  }
                  server.receive(channels.command, bytes.data(), static_cast<int>(bytes.size()), 0);
                } else {
                  server.receive(channels.config, bytes.data(), static_cast<int>(bytes.size()), 0);
                }
              }
            } catch (const std::exception& e) {
              return {Outcome::kUnclear, std::string("the server threw: ") + e.what()};
            }
            return {};
          }};
}

// The `csp` program with mutated argument lists: exit 0 or 1 is accepted, 2 with exactly one line
// on stderr is a clear rejection; anything else (a signal, a sanitizer report, several lines) is not.
Class cli() {
  const std::string real_csv = std::string(CSP_SHARED_DATA_DIR) + "/real/panda_exciting_traj_1.csv";
  const std::vector<std::vector<std::string>> bases = {
      {"model", "--q", "0,-0.785,0,-2.356,0,1.571,0.785", "--dq", "0.1,0,0,0,0,0,0", "--ee", "hand"},
      {"model", "--q=0,-0.5,0,-2,0,1.5,0.7", "--load-mass", "1", "--load-com", "0,0,0.1", "--gravity", "0,0,-9.81"},
      {"workspace", "--samples", "2000", "--seed", "3", "--grid", "20", "--out", "@DIR@"},
      {"emulate", "--duration", "0.02", "--seed", "2", "--clock", "lockstep"},
      {"replay", "--play", "--speed", "0", "@LOG@"},
      {"log", "export", "@LOG@", "--out", "@DIR@/x.csv"},
      {"gap", "--log", real_csv, "--sample-period", "0.01", "--train-fraction", "0.5", "--inertia", "gaz2019"},
      // Every output option: what cannot be written (/proc/self/mem aborted the CSV writer), two
      // outputs in one file, an output that is an input.
      {"emulate", "--duration", "0.02", "--log", "@DIR@/e.csv", "--lcm-log", "@DIR@/e.lcmlog"},
      {"replay", "@LOG@", "--csv", "@DIR@/r.csv"},
      {"workspace", "--samples", "2000", "--grid", "20", "--out", "@DIR@", "--points", "@DIR@/p.csv"},
      {"campaign", CSP_SOURCE_DIR "/tests/campaign/tiny.yaml", "--out", "@DIR@/campaign", "--jobs", "1"},
      {"campaign", "status", "@DIR@/campaign"},
      {"campaign", "collect", "@DIR@/campaign"},
  };
  const std::vector<std::string> values = {"", "-1", "0", "1e308", "nan", "inf", "-inf", "1e-320", "x", "--q", "0,0",
                                           "1,2,3,4,5,6,7,8", "/dev/null", "/", "--help", "9223372036854775808", "1e18",
                                           "/proc/self/mem", "/dev/full", "@DIR@", "@DIR@/missing/x.csv", "@DIR@/e.csv", "@LOG@"};
  // Outputs no command can write (a /proc entry, a device, a directory, a missing directory) or
  // that name another output's or the input's file; one input in four gets one on an output option.
  const std::vector<std::string> output_options = {"--log", "--lcm-log", "--csv", "--out", "--points", "--json", "--report"};
  const std::vector<std::string> bad_outputs = {"/proc/self/mem", "/dev/full", "@DIR@", "@DIR@/missing/x.csv", "@DIR@/e.csv", "@LOG@"};
  return {"cli",
          [bases, values, output_options, bad_outputs](Mutator& m) {
            std::vector<std::string> args = m.pick(bases);
            std::vector<std::size_t> outputs;   // where an output option's value is
            for (std::size_t i = 1; i + 1 < args.size(); ++i)
              if (std::find(output_options.begin(), output_options.end(), args[i]) != output_options.end()) outputs.push_back(i + 1);
            if (!outputs.empty() && m.below(4) == 0) {   // the command as it is, but for one output
              args[m.pick(outputs)] = m.pick(bad_outputs);
              std::string joined;
              for (const std::string& a : args) joined += a + '\x1f';
              return joined;
            }
            const std::size_t edits = 1 + m.below(2);
            for (std::size_t e = 0; e < edits; ++e) {
              const std::size_t i = 1 + m.below(args.size() - 1);
              switch (m.below(4)) {
                case 0: args[i] = m.pick(values); break;
                case 1: args.erase(args.begin() + static_cast<std::ptrdiff_t>(i)); break;
                case 2: args.insert(args.begin() + static_cast<std::ptrdiff_t>(i), m.pick(values)); break;
                case 3: args.push_back(m.pick(values)); break;
              }
            }

            std::string joined;
            for (const std::string& a : args) joined += a + '\x1f';
            return joined;
          },
          nullptr};
}

std::vector<std::string> split_args(const std::string& joined) {
  std::vector<std::string> args;
  std::stringstream in(joined);
  for (std::string a; std::getline(in, a, '\x1f');) args.push_back(a);
  return args;
}

Verdict run_cli(const std::string& joined, const std::string& log) {
  // The log as the class began with it: an input may have written over it (`emulate --log @LOG@`).
  static const std::string base_log = read_text(log);
  write_text(log, base_log);
  std::vector<std::string> args = {CSP_EXECUTABLE};
  for (std::string a : split_args(joined)) {
    if (a == "@LOG@") a = log;
    const std::size_t at = a.find("@DIR@");
    if (at != std::string::npos) a.replace(at, 5, temp_dir());
    args.push_back(a);
  }
  const std::string err = temp_dir() + "/cli.err";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) return {Outcome::kCrash, "cannot start csp"};
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return {Outcome::kHang, "no end within 60 s"};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const std::string text = read_text(err);
  if (!WIFEXITED(status)) return {Outcome::kCrash, "signal " + std::to_string(WTERMSIG(status)) + ": " + text};
  const int code = WEXITSTATUS(status);
  if (code == 0 || code == 1) return {};
  if (code != 2) return {Outcome::kCrash, "exit code " + std::to_string(code) + ": " + text};
  if (std::count(text.begin(), text.end(), '\n') != 1) return {Outcome::kUnclear, "not one line: " + text};
  return {Outcome::kRejected, text.substr(0, text.size() - 1)};
}

// Runs `run(input)` with a watchdog: an input that takes longer than `limit` is a hang, saved and
// reported, and the process ends (the hung call cannot be cancelled).
Verdict with_watchdog(const std::function<Verdict()>& run, std::chrono::seconds limit, const std::string& saved) {
  std::mutex mutex;
  std::condition_variable done_signal;
  bool done = false;
  std::thread watchdog([&] {
    std::unique_lock lock(mutex);
    if (!done_signal.wait_for(lock, limit, [&] { return done; })) {
      std::fprintf(stderr, "csp_fuzz: HANG (no result within %lld s); the input is in %s\n", static_cast<long long>(limit.count()), saved.c_str());
      std::_Exit(1);
    }
  });
  Verdict verdict = run();
  {
    std::lock_guard lock(mutex);
    done = true;
  }
  done_signal.notify_one();
  watchdog.join();
  return verdict;
}

int fuzz(const Class& c, uint64_t budget, uint64_t seed) {
  Mutator mutator(seed);
  std::map<Outcome, uint64_t> counts;
  std::map<Outcome, std::vector<std::string>> examples;
  const std::string saved = std::filesystem::absolute("fuzz-" + c.name + ".input").string();
  const std::string log = temp_dir() + "/cli.lcmlog";
  if (!c.run) {
    const std::vector<uint8_t> base = small_csp_log();
    write_text(log, std::string(base.begin(), base.end()));
  }
  for (uint64_t k = 0; k < budget; ++k) {
    const std::string input = c.generate(mutator);
    write_text(saved, input);   // a crash leaves the input that caused it behind
    const Verdict v = c.run ? with_watchdog([&] { return c.run(input); }, std::chrono::seconds(60), saved) : run_cli(input, log);
    ++counts[v.outcome];
    if (v.outcome != Outcome::kAccepted && v.outcome != Outcome::kRejected && examples[v.outcome].size() < 5) {
      const std::string copy = saved + "." + outcome_name(v.outcome) + std::to_string(examples[v.outcome].size());
      write_text(copy, input);
      examples[v.outcome].push_back(v.detail + " [input: " + copy + "]");
    }
  }
  std::filesystem::remove(saved);
  std::printf("fuzz %-13s %6llu inputs: %llu accepted, %llu rejected clearly, %llu unclear, %llu crashes, %llu hangs\n",
              c.name.c_str(), static_cast<unsigned long long>(budget), static_cast<unsigned long long>(counts[Outcome::kAccepted]),
              static_cast<unsigned long long>(counts[Outcome::kRejected]), static_cast<unsigned long long>(counts[Outcome::kUnclear]),
              static_cast<unsigned long long>(counts[Outcome::kCrash]), static_cast<unsigned long long>(counts[Outcome::kHang]));
  for (const auto& [outcome, list] : examples)
    for (const std::string& e : list) std::printf("  %s: %s\n", outcome_name(outcome), e.c_str());
  return counts[Outcome::kUnclear] + counts[Outcome::kCrash] + counts[Outcome::kHang] == 0 ? 0 : 1;
}

}  // namespace
}  // namespace csp::fuzz

int main(int argc, char** argv) {
  using namespace csp::fuzz;
  std::string which = "all";
  uint64_t budget = 200, seed = 1;
  if (argc % 2 == 0) {
    std::fprintf(stderr, "csp_fuzz: options come in pairs (--class C, --budget N, --seed S)\n");
    return 2;
  }
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--class") which = value;
    else if (key == "--budget") budget = std::stoull(value);
    else if (key == "--seed") seed = std::stoull(value);
    else {
      std::fprintf(stderr, "csp_fuzz: unknown option %s (--class, --budget, --seed)\n", key.c_str());
      return 2;
    }
  }
  const std::vector<std::function<Class()>> makers = {robot_yaml, scenario_yaml, csv_log, lcm_log, lcm_messages, cli};
  int failed = 0, ran = 0;
  for (const auto& make : makers) {
    const Class c = make();
    if (which != "all" && which != c.name) continue;
    ++ran;
    failed += fuzz(c, budget, seed);
  }
  if (ran == 0) {
    std::fprintf(stderr, "csp_fuzz: unknown class %s\n", which.c_str());
    return 2;
  }
  std::filesystem::remove_all(temp_dir());
  return failed == 0 ? 0 : 1;
}
