#include "csp/io/joint_log.hpp"

#include <fcntl.h>
#include <linux/magic.h>
#include <sys/stat.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

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

// The comma-separated fields of a line (views into it); "a,,b," has four.
void split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  for (std::size_t begin = 0;;) {
    const std::size_t comma = line.find(',', begin);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(begin));
      return;
    }
    fields.push_back(line.substr(begin, comma - begin));
    begin = comma + 1;
  }
}

std::string_view trim(std::string_view s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
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
    // The edit distance is at least the difference in length: a long name (up to
    // kMaxColumnNameBytes) is measured against no known one, so the guess stays quick.
    if ((name.size() > known.size() ? name.size() - known.size() : known.size() - name.size()) >= best_distance) continue;
    if (lower(known) == lower(name)) return known;
    const std::size_t distance = edit_distance(name, known);
    if (distance < best_distance) best = known, best_distance = distance;
  }
  return best;
}

std::string unknown_column_message(const std::string& name) {
  std::string message = "unknown column " + quote_input(name);
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

// Why `value` cannot be element `index` of `group`, or empty: not finite, or beyond the group's
// physical bound (kJointLogSchema).
std::string value_problem(const ColumnGroup& group, int index, double value) {
  if (!std::isfinite(value)) return "expected a finite number, got " + number_text(value);
  if (std::abs(value) <= group.limit) return {};
  std::string unit;   // (built in steps: GCC 12 warns falsely of -Wrestrict on " " + string)
  if (!group.unit.empty()) unit.append(" ").append(group.unit);
  return number_text(value) + unit + " is not physically plausible: expected |" + column_name(group, index) +
         "| <= " + number_text(group.limit) + unit + ", far beyond any robot arm (docs/joint-log.md, \"Bounds\")";
}

// One line of at most kMaxLineBytes bytes into `line` (without its newline); false at the end of
// the file. A longer line is refused after reading kMaxLineBytes + 1 bytes of it, not all of it.
bool read_line(std::istream& in, std::string& buffer, std::string_view& line, const std::string& path,
               std::size_t line_number) {
  buffer.resize(kMaxLineBytes + 2);
  in.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  const auto extracted = static_cast<std::size_t>(in.gcount());
  if (in.bad()) throw JointLogError(path + ":" + std::to_string(line_number) + ": cannot read the file");
  if (extracted == 0 && in.eof()) return false;
  const bool cut = in.fail() && !in.eof();   // the buffer filled before a newline
  const std::size_t length = in.eof() ? extracted : extracted - (cut ? 0 : 1);   // less the newline
  if (cut || length > kMaxLineBytes)
    throw JointLogError(path + ":" + std::to_string(line_number) + ": a line longer than " +
                        std::to_string(kMaxLineBytes) + " bytes (a joint log's rows are a few kB); not a joint log?");
  line = std::string_view(buffer.data(), length);
  return true;
}

bool on_pseudo_file_system(const struct statfs& fs) {
  return fs.f_type == PROC_SUPER_MAGIC || fs.f_type == SYSFS_MAGIC || fs.f_type == DEBUGFS_MAGIC;
}

std::string system_error(int error) { return std::strerror(error); }

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
  std::ifstream in(path, std::ios::binary);
  if (!in) throw JointLogError(path + ": cannot open the log (missing or unreadable)");
  std::string buffer;
  std::string_view line;
  if (!read_line(in, buffer, line, path, 1)) throw JointLogError(path + ": empty file, " + expected_columns());
  if (trim(line).empty()) throw JointLogError(path + ":1: an empty header line, " + expected_columns());

  // Header: what each column holds.
  JointLog log;
  log.source = path;
  struct Column {
    const ColumnGroup* group = nullptr;   // null: an extension column
    int index = 0;                        // element of the group, or index into log.extensions
    std::string name;
  };
  std::vector<std::string_view> fields;
  split(line, fields);
  std::vector<Column> columns;
  std::map<std::string, std::size_t> seen;
  std::vector<int> present(kJointLogSchema.size(), 0);
  for (std::size_t c = 0; c < fields.size(); ++c) {
    const std::string_view text = trim(fields[c]);
    const std::string where = path + ":1: column " + std::to_string(c + 1) + ": ";
    if (text.size() > kMaxColumnNameBytes)
      throw JointLogError(where + "a column name of " + std::to_string(text.size()) + " bytes, " + quote_input(text) +
                          " (at most " + std::to_string(kMaxColumnNameBytes) + "); " + expected_columns());
    const std::string name(text);
    if (!seen.emplace(name, c).second) throw JointLogError(where + "duplicate column " + quote_input(name));
    if (const KnownColumn* known = find_known(name)) {
      columns.push_back({&kJointLogSchema[known->group], known->index, name});
      ++present[known->group];
    } else if (name.size() > kExtensionPrefix.size() && name.rfind(kExtensionPrefix, 0) == 0) {
      columns.push_back({nullptr, static_cast<int>(log.extensions.size()), name});
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
  const std::size_t width = columns.size();
  for (std::size_t line_number = 2; read_line(in, buffer, line, path, line_number); ++line_number) {
    if (trim(line).empty()) continue;
    split(line, fields);
    const auto where = [&] { return path + ":" + std::to_string(line_number); };
    const auto in_column = [&](std::size_t c) {
      return where() + ": column " + std::to_string(c + 1) + " (" + columns[c].name + "): ";
    };
    if (fields.size() != width)
      throw JointLogError(where() + ": expected " + std::to_string(width) + " comma-separated values, got " +
                          std::to_string(fields.size()));
    for (const ColumnGroup* group : groups) with_series(log, *group, [](auto& series) { series.emplace_back(); });
    for (ExtensionColumn& extension : log.extensions) extension.values.emplace_back();
    for (std::size_t c = 0; c < width; ++c) {
      const std::string_view text = trim(fields[c]);
      const Column& column = columns[c];
      if (text.size() > kMaxFieldBytes)
        throw JointLogError(in_column(c) + "a value of " + std::to_string(text.size()) + " bytes, " + quote_input(text) +
                            " (at most " + std::to_string(kMaxFieldBytes) + ")");
      if (column.group && column.group->text) {
        if (text.empty()) throw JointLogError(in_column(c) + "expected a word, got nothing");
        with_series(log, *column.group, [&](auto& series) {
          if constexpr (std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>)
            series.back() = std::string(text);
        });
        continue;
      }
      double value = 0.0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
        throw JointLogError(in_column(c) + "expected a finite number, got " + quote_input(text));
      if (!column.group) {
        log.extensions[static_cast<std::size_t>(column.index)].values.back() = value;
        continue;
      }
      if (const std::string problem = value_problem(*column.group, column.index, value); !problem.empty())
        throw JointLogError(in_column(c) + problem);
      with_series(log, *column.group, [&](auto& series) {
        if constexpr (!std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>)
          element_number(series.back(), column.index) = value;
      });
    }
    const std::size_t n = log.size();
    if (n >= 2 && log.t[n - 1] <= log.t[n - 2])
      throw JointLogError(where() + ": time must increase: t = " + number_text(log.t[n - 1]) + " after " +
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
            if (const std::string problem = value_problem(group, j, element_number(series[k], j)); !problem.empty()) {
              // t itself may be what is wrong: name the row by its number alone then.
              const std::string row = std::isfinite(log.t[k]) && std::abs(log.t[k]) <= kJointLogSchema[0].limit
                                          ? where(k)
                                          : log.source + ": row " + std::to_string(k + 1) + ": ";
              throw JointLogError(row + "column `" + column_name(group, j) + "`: " + problem);
            }
    });
  }
  for (std::size_t k = 1; k < n; ++k)
    if (log.t[k] <= log.t[k - 1])
      throw JointLogError(where(k) + "time must increase: t = " + number_text(log.t[k]) + " after " +
                          number_text(log.t[k - 1]));
  for (const ExtensionColumn& extension : log.extensions) {
    if (extension.values.size() != n)
      throw JointLogError(log.source + ": column " + quote_input(extension.name) + " has " +
                          std::to_string(extension.values.size()) + " rows, t has " + std::to_string(n));
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(extension.values[k]))
        throw JointLogError(where(k) + "column " + quote_input(extension.name) + ": expected a finite number, got " +
                            number_text(extension.values[k]));
  }
  if (n < 2) throw JointLogError(log.source + ": expected at least 2 data rows, got " + std::to_string(n));
}

JointLogCsvWriter::JointLogCsvWriter(const std::string& path, const JointLog& layout)
    : path_(path), extensions_(layout.extensions.size()) {
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
  if (const std::string problem = output_file_problem(path); !problem.empty())
    throw JointLogError(path + ": cannot write the log: " + problem);
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) throw JointLogError(path + ": cannot write the log: " + system_error(errno));
  // The memory of a row is reserved once: no allocation per row in the 1 kHz loop.
  buffer_.reserve(kRowBytes);
  buffer_ = header;
  buffer_ += '\n';
  write_out();   // the header now: a file that cannot be written fails before any row
}

JointLogCsvWriter::~JointLogCsvWriter() {
  if (fd_ >= 0) ::close(fd_);   // every row is written already
}

void JointLogCsvWriter::write_row(const JointLog& log, std::size_t row) {
  if (!failure_.empty()) throw JointLogError(failure_);
  const std::size_t line_start = buffer_.size();
  for (const ColumnGroup* group : groups_) {
    with_series(log, *group, [&](const auto& series) {
      if constexpr (std::is_same_v<typename std::decay_t<decltype(series)>::value_type, std::string>) {
        const std::string& text = series[row];
        if (text.empty() || text.find_first_of(", \t\r\n") != std::string::npos) {
          buffer_.resize(line_start);   // no part of the row stays
          throw JointLogError(path_ + ": column `" + std::string(group->name) + "`: cannot write " + quote_input(text) +
                              " (expected a word without commas or spaces)");
        }
        buffer_ += text;
        buffer_ += ',';
      } else {
        for (int j = 0; j < group->width; ++j) {
          append_number(buffer_, element_number(series[row], j));
          buffer_ += ',';
        }
      }
    });
  }
  for (std::size_t e = 0; e < extensions_; ++e) {
    append_number(buffer_, log.extensions[e].values[row]);
    buffer_ += ',';
  }
  buffer_.back() = '\n';
  // Each row reaches the file at once (one write per row, as an unbuffered stream would): a reader
  // of the file sees every row written so far, and a process killed mid-run loses none.
  write_out();
}

void JointLogCsvWriter::flush() {
  if (!failure_.empty()) throw JointLogError(failure_);
  if (!buffer_.empty()) write_out();
}

void JointLogCsvWriter::write_out() {
  std::size_t written = 0;
  while (written < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + written, buffer_.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail_write(n < 0 ? errno : EIO, written);
    written += static_cast<std::size_t>(n);
  }
  complete_bytes_ += buffer_.size();
  buffer_.clear();
}

void JointLogCsvWriter::fail_write(int error, std::size_t written) {
  // The file holds complete_bytes_ of whole lines and then the first `written` bytes of the
  // buffer, which may end inside a row: cut it after the last whole one, so that what was written
  // stays a valid log and no row written before is lost.
  const std::size_t last_newline = std::string_view(buffer_.data(), written).rfind('\n');
  const uint64_t keep = complete_bytes_ + (last_newline == std::string_view::npos ? 0 : last_newline + 1);
  struct stat status {};
  if (::fstat(fd_, &status) == 0 && S_ISREG(status.st_mode)) (void)::ftruncate(fd_, static_cast<off_t>(keep));
  ::close(fd_);
  fd_ = -1;
  buffer_.clear();
  failure_ = path_ + ": writing the log failed (" + system_error(error) + "); the file ends at its last complete row";
  throw JointLogError(failure_);
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

std::vector<NumericColumn> numeric_columns(const JointLog& log) {
  std::vector<NumericColumn> columns;
  for (const ColumnGroup& group : kJointLogSchema) {
    if (group.text || rows_of(log, group) != log.size() || log.size() == 0) continue;   // text, or absent
    with_series(log, group, [&](const auto& series) {
      for (int j = 0; j < group.width; ++j) {
        NumericColumn& column = columns.emplace_back(NumericColumn{column_name(group, j), {}});
        column.values.reserve(series.size());
        for (const auto& value : series) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(value)>, std::string>)   // text groups were left out
            column.values.push_back(element_number(value, j));
        }
      }
    });
  }
  for (const ExtensionColumn& extension : log.extensions) columns.push_back({extension.name, extension.values});
  return columns;
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

std::string quote_input(std::string_view text, std::size_t max_bytes) {
  std::size_t shown = std::min(text.size(), max_bytes);
  // Not inside a UTF-8 sequence: back to the start of the character that does not fit.
  if (shown < text.size())
    while (shown > 0 && (static_cast<unsigned char>(text[shown]) & 0xC0) == 0x80) --shown;
  std::string out = "`";
  for (std::size_t i = 0; i < shown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7F) {
      static const char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  out += '`';
  if (shown < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

namespace {

// Why a path that exists cannot be written into (a file), or empty.
std::string existing_output_problem(const std::string& path, const struct stat& status, bool directory) {
  if (directory ? !S_ISDIR(status.st_mode) : S_ISDIR(status.st_mode))
    return directory ? "is not a directory" : "is a directory; give a file name";
  if (!directory && !S_ISREG(status.st_mode))
    return "is not a regular file (a device, FIFO or socket); give a file on a disk";
  struct statfs fs {};
  if (::statfs(path.c_str(), &fs) == 0 && on_pseudo_file_system(fs))
    return std::string("is a /proc or /sys entry, not a ") + (directory ? "directory" : "file") + " on a disk";
  if (::access(path.c_str(), directory ? W_OK | X_OK : W_OK) != 0)
    return std::string("cannot be written (") + system_error(errno) + ")";
  return {};
}

// `path`'s status in `status`; errno's reason if it cannot be reached (ENOENT: missing).
int status_of(const std::string& path, struct stat& status) { return ::stat(path.c_str(), &status) == 0 ? 0 : errno; }

std::string parent_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? "." : parent.string();
}

}  // namespace

std::string output_file_problem(const std::string& path) {
  if (path.empty()) return "no file name given";
  struct stat status {};
  const int error = status_of(path, status);
  if (error == 0) return existing_output_problem(path, status, false);
  if (error != ENOENT) return "cannot be reached (" + system_error(error) + ")";
  if (!path.empty() && path.back() == '/') return "names a directory (ends with /); give a file name";
  // A new file: its directory must exist and take it.
  const std::string parent = parent_of(path);
  const int parent_error = status_of(parent, status);
  if (parent_error == ENOENT) return "its directory " + parent + " does not exist";
  if (parent_error != 0) return "its directory " + parent + " cannot be reached (" + system_error(parent_error) + ")";
  if (const std::string problem = existing_output_problem(parent, status, true); !problem.empty())
    return "its directory " + parent + " " + problem;
  return {};
}

std::string output_directory_problem(const std::string& path) {
  if (path.empty()) return "no directory name given";
  struct stat status {};
  const int error = status_of(path, status);
  if (error == 0) return existing_output_problem(path, status, true);
  if (error != ENOENT) return "cannot be reached (" + system_error(error) + ")";
  // Created with its missing parents: the nearest existing one must take them.
  std::filesystem::path ancestor = std::filesystem::absolute(path).lexically_normal();
  while (ancestor.has_relative_path()) {
    ancestor = ancestor.parent_path();
    const int ancestor_error = status_of(ancestor.string(), status);
    if (ancestor_error == ENOENT) continue;
    if (ancestor_error != 0) return "cannot be created: " + ancestor.string() + " cannot be reached (" + system_error(ancestor_error) + ")";
    if (const std::string problem = existing_output_problem(ancestor.string(), status, true); !problem.empty())
      return "cannot be created: " + ancestor.string() + " " + problem;
    return {};
  }
  return {};
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat first {}, second {};
  if (::stat(a.c_str(), &first) == 0 && ::stat(b.c_str(), &second) == 0)
    return first.st_dev == second.st_dev && first.st_ino == second.st_ino;
  std::error_code error_a, error_b;
  const std::filesystem::path canonical_a = std::filesystem::weakly_canonical(std::filesystem::absolute(a), error_a);
  const std::filesystem::path canonical_b = std::filesystem::weakly_canonical(std::filesystem::absolute(b), error_b);
  if (error_a || error_b) return std::filesystem::absolute(a).lexically_normal() == std::filesystem::absolute(b).lexically_normal();
  return canonical_a == canonical_b;
}

}  // namespace csp
