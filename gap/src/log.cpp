#include "csp/gap/log.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace csp::gap {
namespace {

// Column groups of the format; each has seven joint columns named prefix1..prefix7.
struct ColumnGroup {
  const char* prefix;
  bool required;
};
constexpr ColumnGroup kGroups[] = {{"q", true}, {"dq", true}, {"tau_J", true}, {"ddq", false}, {"tau_J_d", false}};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return {};
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

std::string expected_columns() {
  return "expected t, q1..q7, dq1..dq7, tau_J1..tau_J7 (optional ddq1..ddq7, tau_J_d1..tau_J_d7)";
}

}  // namespace

JointLog read_log_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw LogError(path + ": cannot open the log (missing or unreadable)");
  std::string line;
  if (!std::getline(in, line)) throw LogError(path + ": empty file, " + expected_columns());

  // Header: map each column name to its index.
  const std::vector<std::string> header = split(line);
  std::map<std::string, std::size_t> index;
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string name = trim(header[c]);
    bool known = name == "t";
    for (const auto& group : kGroups)
      for (int j = 1; j <= kNumJoints; ++j) known = known || name == group.prefix + std::to_string(j);
    if (!known)
      throw LogError(path + ":1: column " + std::to_string(c + 1) + ": unknown column `" + name + "`; " +
                     expected_columns());
    if (!index.emplace(name, c).second)
      throw LogError(path + ":1: column " + std::to_string(c + 1) + ": duplicate column `" + name + "`");
  }
  auto column = [&](const std::string& name) -> std::optional<std::size_t> {
    const auto it = index.find(name);
    return it == index.end() ? std::nullopt : std::optional(it->second);
  };
  if (!column("t")) throw LogError(path + ":1: missing column `t`; " + expected_columns());
  bool has_group[std::size(kGroups)] = {};
  for (std::size_t g = 0; g < std::size(kGroups); ++g) {
    int present = 0;
    for (int j = 1; j <= kNumJoints; ++j) present += column(kGroups[g].prefix + std::to_string(j)).has_value();
    has_group[g] = present == kNumJoints;
    if (present == kNumJoints || (present == 0 && !kGroups[g].required)) continue;
    for (int j = 1; j <= kNumJoints; ++j)
      if (!column(kGroups[g].prefix + std::to_string(j)))
        throw LogError(path + ":1: missing column `" + kGroups[g].prefix + std::to_string(j) + "`; " +
                       expected_columns());
  }

  JointLog log;
  log.source = path;
  std::vector<double> values(header.size());
  for (std::size_t line_number = 2; std::getline(in, line); ++line_number) {
    if (trim(line).empty()) continue;
    const std::vector<std::string> fields = split(line);
    const std::string where = path + ":" + std::to_string(line_number);
    if (fields.size() != header.size())
      throw LogError(where + ": expected " + std::to_string(header.size()) + " comma-separated values, got " +
                     std::to_string(fields.size()));
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string text = trim(fields[c]);
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), values[c]);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(values[c]))
        throw LogError(where + ": column " + std::to_string(c + 1) + " (" + trim(header[c]) +
                       "): expected a finite number, got `" + text + "`");
    }
    const double t = values[*column("t")];
    if (!log.t.empty() && t <= log.t.back())
      throw LogError(where + ": time must increase: t = " + std::to_string(t) + " after " +
                     std::to_string(log.t.back()));
    log.t.push_back(t);
    auto joints = [&](const char* prefix) {
      Vector7 v;
      for (int j = 0; j < kNumJoints; ++j) v[j] = values[*column(prefix + std::to_string(j + 1))];
      return v;
    };
    log.q.push_back(joints("q"));
    log.dq.push_back(joints("dq"));
    log.tau.push_back(joints("tau_J"));
    if (has_group[3]) log.ddq.push_back(joints("ddq"));
  }
  if (log.size() < 2) throw LogError(path + ": expected at least 2 data rows, got " + std::to_string(log.size()));
  return log;
}

void write_log_csv(const std::string& path, const JointLog& log) {
  std::ofstream out(path);
  if (!out) throw LogError("cannot write " + path);
  out << "t";
  for (const char* prefix : {"q", "dq", "tau_J"})
    for (int j = 1; j <= kNumJoints; ++j) out << ',' << prefix << j;
  out << '\n';
  out.precision(10);
  for (std::size_t k = 0; k < log.size(); ++k) {
    out << log.t[k];
    for (const auto* series : {&log.q, &log.dq, &log.tau})
      for (int j = 0; j < kNumJoints; ++j) out << ',' << (*series)[k][j];
    out << '\n';
  }
  if (!out) throw LogError("cannot write " + path);
}

JointLog slice(const JointLog& log, double t_begin, double t_end) {
  JointLog part;
  part.source = log.source;
  for (std::size_t k = 0; k < log.size(); ++k) {
    if (log.t[k] < t_begin || log.t[k] >= t_end) continue;
    part.t.push_back(log.t[k]);
    part.q.push_back(log.q[k]);
    part.dq.push_back(log.dq[k]);
    part.tau.push_back(log.tau[k]);
    if (!log.ddq.empty()) part.ddq.push_back(log.ddq[k]);
  }
  return part;
}

}  // namespace csp::gap
