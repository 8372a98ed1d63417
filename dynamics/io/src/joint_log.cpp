#include "csp/io/joint_log.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace csp {
namespace {

// Element types of the groups: their width, and their j-th number.
template <class T>
struct Element;
template <>
struct Element<double> {
  static constexpr int width = 1;
};
template <int N>
struct Element<Eigen::Matrix<double, N, 1>> {
  static constexpr int width = N;
};
template <>
struct Element<std::string> {
  static constexpr int width = 1;
};

// The j-th number of one row's element (a scalar, or a vector's entry).
double& element_number(double& value, int) { return value; }
double element_number(const double& value, int) { return value; }
template <int N>
double& element_number(Eigen::Matrix<double, N, 1>& value, int j) { return value[j]; }
template <int N>
double element_number(const Eigen::Matrix<double, N, 1>& value, int j) { return value[j]; }

template <class T>
constexpr int width_of(std::vector<T> JointLog::*) { return Element<T>::width; }
template <class T>
constexpr bool is_text(std::vector<T> JointLog::*) { return std::is_same_v<T, std::string>; }

// The schema's widths and kinds are those of the JointLog members it points to.
constexpr bool schema_matches_members() {
  for (const ColumnGroup& group : kJointLogSchema) {
    const bool width_ok = std::visit([&](auto member) { return width_of(member) == group.width; }, group.member);
    const bool kind_ok = std::visit([&](auto member) { return is_text(member) == group.text; }, group.member);
    if (!width_ok || !kind_ok) return false;
  }
  return true;
}
static_assert(schema_matches_members(), "kJointLogSchema: a width or kind differs from its JointLog member");

// Calls `visit(series)` with the vector of `group` in `log` (const or not).
template <class Log, class Visit>
decltype(auto) with_series(Log& log, const ColumnGroup& group, Visit&& visit) {
  return std::visit([&](auto member) -> decltype(auto) { return visit(log.*member); }, group.member);
}

std::size_t rows_of(const JointLog& log, const ColumnGroup& group) {
  return with_series(log, group, [](const auto& series) { return series.size(); });
}

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

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string expected_columns() {
  return "expected t, q1..q7, dq1..dq7, tau_J1..tau_J7 (optional groups and x_ columns: docs/joint-log.md)";
}

struct KnownColumn {
  std::size_t group;   // index into kJointLogSchema
  int index;           // element of the group
};

// Every column name of the schema, in schema order.
const std::vector<std::pair<std::string, KnownColumn>>& known_columns() {
  static const std::vector<std::pair<std::string, KnownColumn>> columns = [] {
    std::vector<std::pair<std::string, KnownColumn>> all;
    for (std::size_t g = 0; g < kJointLogSchema.size(); ++g)
      for (int j = 0; j < kJointLogSchema[g].width; ++j) all.push_back({column_name(kJointLogSchema[g], j), {g, j}});
    return all;
  }();
  return columns;
}

const KnownColumn* find_known(const std::string& name) {
  for (const auto& [known, column] : known_columns())
    if (known == name) return &column;
  return nullptr;
}

// Levenshtein distance (insertions, deletions, substitutions).
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(previous, current);
  }
  return previous[b.size()];
}

// The known column a typo most likely meant: equal but for case, else within 2 edits; or empty.
std::string closest_known(const std::string& name) {
  std::string best;
  std::size_t best_distance = 3;
  for (const auto& [known, column] : known_columns()) {
    if (lower(known) == lower(name)) return known;
    const std::size_t distance = edit_distance(name, known);
    if (distance < best_distance) best = known, best_distance = distance;
  }
  return best;
}

std::string unknown_column_message(const std::string& name) {
  std::string message = "unknown column `" + name + "`";
  const std::string guess = closest_known(name);
  message += guess.empty() ? "." : "; did you mean `" + guess + "`?";
  message += " Columns of your own must start with `" + std::string(kExtensionPrefix) + "`; " + expected_columns();
  return message;
}

std::string number_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

void append_number(std::string& line, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  line.append(buffer, result.ptr);
}

// Refuses what is not a regular file before opening it: opening a FIFO would wait for a writer.
void require_regular_file(const std::string& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) throw JointLogError(path + ": cannot open the log (missing or unreadable)");
  if (!std::filesystem::is_regular_file(status))
    throw JointLogError(path + ": not a regular file (a directory, FIFO or device); expected a joint log");
}

}  // namespace

std::string column_name(const ColumnGroup& group, int index) {
  return group.width == 1 ? std::string(group.name) : std::string(group.name) + std::to_string(index + 1);
}

void JointLog::clear_rows() {
  for (const ColumnGroup& group : kJointLogSchema) with_series(*this, group, [](auto& series) { series.clear(); });
  for (ExtensionColumn& extension : extensions) extension.values.clear();
}

JointLog read_joint_log_csv(const std::string& path) {
  require_regular_file(path);
  std::ifstream in(path);
  if (!in) throw JointLogError(path + ": cannot open the log (missing or unreadable)");
  std::string line;
  if (!std::getline(in, line)) throw JointLogError(path + ": empty file, " + expected_columns());

  // Header: what each column holds.
  JointLog log;
  log.source = path;
  struct Column {
    const ColumnGroup* group = nullptr;   // null: an extension column
    int index = 0;                        // element of the group, or index into log.extensions
  };
  const std::vector<std::string> header = split(line);
  std::vector<Column> columns;
  std::map<std::string, std::size_t> seen;
  std::vector<int> present(kJointLogSchema.size(), 0);
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string name = trim(header[c]);
    const std::string where = path + ":1: column " + std::to_string(c + 1) + ": ";
    if (!seen.emplace(name, c).second) throw JointLogError(where + "duplicate column `" + name + "`");
    if (const KnownColumn* known = find_known(name)) {
      columns.push_back({&kJointLogSchema[known->group], known->index});
      ++present[known->group];
    } else if (name.size() > kExtensionPrefix.size() && name.rfind(kExtensionPrefix, 0) == 0) {
      columns.push_back({nullptr, static_cast<int>(log.extensions.size())});
      log.extensions.push_back({name, {}});
    } else {
      throw JointLogError(where + unknown_column_message(name));
    }
  }
  // A group is all there or (if optional) not at all.
  std::vector<const ColumnGroup*> groups;
  for (std::size_t g = 0; g < kJointLogSchema.size(); ++g) {
    const ColumnGroup& group = kJointLogSchema[g];
    if (present[g] == group.width) {
      groups.push_back(&group);
      continue;
    }
    if (present[g] == 0 && !group.required) continue;
    for (int j = 0; j < group.width; ++j)
      if (!seen.count(column_name(group, j)))
        throw JointLogError(path + ":1: missing column `" + column_name(group, j) + "`; " + expected_columns());
  }

  // Rows.
  for (std::size_t line_number = 2; std::getline(in, line); ++line_number) {
    if (trim(line).empty()) continue;
    const std::vector<std::string> fields = split(line);
    const std::string where = path + ":" + std::to_string(line_number);
    if (fields.size() != header.size())
      throw JointLogError(where + ": expected " + std::to_string(header.size()) + " comma-separated values, got " +
                          std::to_string(fields.size()));
    for (const ColumnGroup* group : groups) with_series(log, *group, [](auto& series) { series.emplace_back(); });
    for (ExtensionColumn& extension : log.extensions) extension.values.emplace_back();
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string text = trim(fields[c]);
      const Column& column = columns[c];
      if (column.group && column.group->text) {
        if (text.empty()) throw JointLogError(where + ": column " + std::to_string(c + 1) + " (" + trim(header[c]) + "): expected a word, got nothing");
        with_series(log, *column.group, [&](auto& series) {
          if constexpr (std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>) series.back() = text;
        });
        continue;
      }
      double value = 0.0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
        throw JointLogError(where + ": column " + std::to_string(c + 1) + " (" + trim(header[c]) +
                            "): expected a finite number, got `" + text + "`");
      if (!column.group) {
        log.extensions[column.index].values.back() = value;
        continue;
      }
      with_series(log, *column.group, [&](auto& series) {
        if constexpr (!std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>)
          element_number(series.back(), column.index) = value;
      });
    }
    const std::size_t n = log.size();
    if (n >= 2 && log.t[n - 1] <= log.t[n - 2])
      throw JointLogError(where + ": time must increase: t = " + number_text(log.t[n - 1]) + " after " +
                          number_text(log.t[n - 2]));
  }
  check_joint_log(log);   // the row count (the rest is checked line by line above)
  return log;
}

void check_joint_log(const JointLog& log) {
  const std::size_t n = log.size();
  const auto where = [&](std::size_t k) {
    return log.source + ": row " + std::to_string(k + 1) + " (t = " + number_text(log.t[k]) + " s): ";
  };
  for (const ColumnGroup& group : kJointLogSchema) {
    const std::size_t rows = rows_of(log, group);
    if (rows != n && (rows != 0 || group.required))
      throw JointLogError(log.source + ": group `" + std::string(group.name) + "` has " + std::to_string(rows) +
                          " rows, t has " + std::to_string(n));
    if (group.text) continue;
    with_series(log, group, [&](const auto& series) {
      if constexpr (!std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>)
        for (std::size_t k = 0; k < series.size(); ++k)
          for (int j = 0; j < group.width; ++j)
            if (!std::isfinite(element_number(series[k], j)))
              throw JointLogError(where(k) + "column `" + column_name(group, j) + "`: expected a finite number, got " +
                                  number_text(element_number(series[k], j)));
    });
  }
  for (std::size_t k = 1; k < n; ++k)
    if (log.t[k] <= log.t[k - 1])
      throw JointLogError(where(k) + "time must increase: t = " + number_text(log.t[k]) + " after " +
                          number_text(log.t[k - 1]));
  for (const ExtensionColumn& extension : log.extensions)
    if (extension.values.size() != n)
      throw JointLogError(log.source + ": column `" + extension.name + "` has " + std::to_string(extension.values.size()) +
                          " rows, t has " + std::to_string(n));
  if (n < 2) throw JointLogError(log.source + ": expected at least 2 data rows, got " + std::to_string(n));
}

JointLogCsvWriter::JointLogCsvWriter(const std::string& path, const JointLog& layout)
    : path_(path), out_(path, std::ios::out | std::ios::trunc), extensions_(layout.extensions.size()) {
  if (!out_) throw JointLogError(path + ": cannot write the log file");
  std::string header;
  for (const ColumnGroup& group : kJointLogSchema) {
    if (rows_of(layout, group) == 0) {
      if (group.required) throw JointLogError(path + ": a joint log needs the group `" + std::string(group.name) + "`");
      continue;
    }
    groups_.push_back(&group);
    for (int j = 0; j < group.width; ++j) {
      if (!header.empty()) header += ',';
      header += column_name(group, j);
    }
  }
  for (const ExtensionColumn& extension : layout.extensions) {
    header += ',';
    header += extension.name;
  }
  out_ << header << '\n';
}

void JointLogCsvWriter::write_row(const JointLog& log, std::size_t row) {
  line_.clear();
  for (const ColumnGroup* group : groups_) {
    with_series(log, *group, [&](const auto& series) {
      if constexpr (std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>) {
        const std::string& text = series[row];
        if (text.empty() || text.find_first_of(", \t\r\n") != std::string::npos)
          throw JointLogError(path_ + ": column `" + std::string(group->name) + "`: cannot write `" + text +
                              "` (expected a word without commas or spaces)");
        line_ += text;
        line_ += ',';
      } else {
        for (int j = 0; j < group->width; ++j) {
          append_number(line_, element_number(series[row], j));
          line_ += ',';
        }
      }
    });
  }
  for (std::size_t e = 0; e < extensions_; ++e) {
    append_number(line_, log.extensions[e].values[row]);
    line_ += ',';
  }
  line_.back() = '\n';
  out_ << line_;
  if (!out_) fail_write();
}

void JointLogCsvWriter::flush() {
  out_.flush();
  if (!out_) fail_write();
}

void JointLogCsvWriter::fail_write() {
  // Part of a row may have reached the file: cut it at the last complete row, so that what was
  // written stays a valid log (a regular file; a device such as /dev/full holds nothing).
  out_.close();
  std::error_code error;
  if (std::filesystem::is_regular_file(path_, error)) {
    std::ifstream in(path_, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    std::filesystem::resize_file(path_, text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1, error);
  }
  throw JointLogError(path_ + ": writing the log failed (disk full or the file system refused it); the file ends at its "
                      "last complete row");
}

void write_joint_log_csv(const std::string& path, const JointLog& log) {
  JointLogCsvWriter writer(path, log);
  for (std::size_t k = 0; k < log.size(); ++k) writer.write_row(log, k);
  writer.flush();
}

JointLog slice(const JointLog& log, double t_begin, double t_end) {
  JointLog part;
  part.source = log.source;
  const auto inside = [&](std::size_t k) { return log.t[k] >= t_begin && log.t[k] < t_end; };
  for (const ColumnGroup& group : kJointLogSchema)
    std::visit(
        [&](auto member) {
          const auto& in = log.*member;
          if (in.size() != log.size()) return;   // an absent group
          for (std::size_t k = 0; k < in.size(); ++k)
            if (inside(k)) (part.*member).push_back(in[k]);
        },
        group.member);
  for (const ExtensionColumn& extension : log.extensions) {
    ExtensionColumn& out = part.extensions.emplace_back(ExtensionColumn{extension.name, {}});
    for (std::size_t k = 0; k < extension.values.size(); ++k)
      if (inside(k)) out.values.push_back(extension.values[k]);
  }
  return part;
}

void append_rows(JointLog& log, const JointLog& part, double time_shift) {
  const std::size_t first = log.size();
  for (const ColumnGroup& group : kJointLogSchema)
    std::visit(
        [&](auto member) {
          const auto& in = part.*member;
          if (in.size() == part.size()) (log.*member).insert((log.*member).end(), in.begin(), in.end());
        },
        group.member);
  for (std::size_t k = first; k < log.size(); ++k) log.t[k] -= time_shift;
  for (std::size_t i = 0; i < part.extensions.size(); ++i) {
    if (log.extensions.size() <= i) log.extensions.push_back({part.extensions[i].name, {}});
    std::vector<double>& values = log.extensions[i].values;
    values.insert(values.end(), part.extensions[i].values.begin(), part.extensions[i].values.end());
  }
}

}  // namespace csp
