// The joint log: one row per robot cycle (or per sample of a real robot's log) with libfranka's
// field names, units and frames. One format for every writer and reader: `csp emulate --log`,
// `csp log export` / `import`, `csp gap --log`, the gap generator, and real-robot logs such as
// ../shared/data/real/panda_exciting_traj_1.csv. The columns, their units and the extension rule
// are documented in docs/joint-log.md; an LCM log (bridge/) is a second container of the same rows.
//
// CSV: a header row naming the columns (any order when reading), then one row of comma-separated
// values per sample. Reading validates every field and throws JointLogError naming the file, the
// line, the column and what was expected. Writing gives the same bytes for the same data (numbers
// in their shortest exact form).
#pragma once

#include <array>
#include <cstdint>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "csp/dynamics/spatial.hpp"

namespace csp {

class JointLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Vector16 = Eigen::Matrix<double, 16, 1>;   // a 4x4 pose, column-major as libfranka's O_T_EE

// A user's own column: a number per row, carried through reading and writing.
struct ExtensionColumn {
  std::string name;   // starts with kExtensionPrefix
  std::vector<double> values;
};

struct JointLog {
  std::string source;   // file name (or generator description), for messages

  // Required.
  std::vector<double> t;          // time [s], strictly increasing, not necessarily uniform
  std::vector<Vector7> q, dq;     // measured joint position [rad] and velocity [rad/s]
  std::vector<Vector7> tau_J;     // measured link-side joint torque, gravity included [N m]

  // Optional: empty, or one entry per row.
  std::vector<Vector7> ddq;                   // joint acceleration [rad/s^2] (not reported by a Franka)
  std::vector<Vector7> tau_J_d;               // desired link-side torque without gravity [N m]
  std::vector<Vector7> q_d, dq_d, ddq_d;      // desired joint position, velocity, acceleration
  std::vector<Vector7> dtau_J;                // derivative of tau_J [N m/s]
  std::vector<Vector7> tau_ext_hat_filtered;  // filtered external torque estimate [N m]
  std::vector<Vector6> O_F_ext_hat_K;         // external wrench on K in the base frame [N, N m]
  std::vector<Vector16> O_T_EE;               // measured EE pose in the base frame, column-major
  std::vector<std::string> robot_mode;        // libfranka's RobotMode name, e.g. "Move"
  std::vector<double> command_received;       // 1 if the cycle applied a command, else 0
  std::vector<double> control_command_success_rate;   // share of the last 100 commands received
  std::vector<std::string> current_errors;    // libfranka's error names as "[a|b]", "[]" without

  std::vector<ExtensionColumn> extensions;    // x_... columns, in file order

  std::size_t size() const { return t.size(); }
  // Empties every group and extension column (the columns stay, and their memory).
  void clear_rows();
};

// Where a group's values live in a JointLog: one vector per group, of the group's element type.
using GroupMember = std::variant<std::vector<double> JointLog::*, std::vector<Vector6> JointLog::*,
                                 std::vector<Vector7> JointLog::*, std::vector<Vector16> JointLog::*,
                                 std::vector<std::string> JointLog::*>;

// A column group of the format: `width` columns named name1..nameN, or `name` alone when the
// width is 1. Text groups hold words (no comma, no space); the others finite numbers.
struct ColumnGroup {
  std::string_view name;
  int width;
  std::string_view unit;
  std::string_view meaning;
  bool required;
  bool text;
  GroupMember member;
  // The largest magnitude a value may have (numeric groups): a generous physical bound, far beyond
  // any Franka arm (kJointLogSchema says why for each), so that a value past it is a corrupt or
  // foreign log, not a robot's. Infinity: only finite.
  double limit = std::numeric_limits<double>::infinity();
};

// The schema, in the column order writers use: the real Panda log's t, q, dq, tau_J first, then
// the optional groups as `csp emulate --log` has always written them.
// Bounds (ColumnGroup::limit), each about ten times what any Franka arm reaches, so that a real
// or emulated log never comes near them and a corrupt one (1e300 N m) is refused at its line:
//   t 1e9 s: over 30 years of robot time; keeps t in ms and us (LCM utime) well inside int64.
//   q, q_d 10 rad: one and a half turns either way; every Panda / FR3 joint stays in [-3.1, 4.7] rad.
//   dq, dq_d 50 rad/s: ten times the fastest Franka joint (FR3 joints 5-7: 5.26 rad/s).
//   ddq, ddq_d 1e5 rad/s^2: 5000 times the acceleration limits (10-20 rad/s^2): room for a noisy
//     velocity differentiated at 1 kHz and a motion generator's raw command.
//   tau_J, tau_J_d, tau_ext_hat_filtered 1000 N m: more than ten times the largest joint torque
//     (87 N m); no joint of a collaborative arm holds it.
//   dtau_J 1e7 N m/s: 10^4 times the limit (1000 N m/s); tau_J across its whole range in 0.2 ms.
//   O_F_ext_hat_K 1e6 N, N m: a Franka carries 3 kg (30 N); the estimate through a near-singular
//     Jacobian may be large, but not a million newtons.
//   O_T_EE 100: the rotation's entries are within 1, the translation within the 0.855 m reach.
// (command_received and control_command_success_rate are no physical quantities: only finite.)
inline constexpr std::array<ColumnGroup, 17> kJointLogSchema = {{
    {"t", 1, "s", "time since the robot started (1 ms steps on a Franka)", true, false, &JointLog::t, 1e9},
    {"q", 7, "rad", "measured joint position", true, false, &JointLog::q, 10.0},
    {"dq", 7, "rad/s", "measured joint velocity", true, false, &JointLog::dq, 50.0},
    {"tau_J", 7, "N m", "measured link-side joint torque, gravity included", true, false, &JointLog::tau_J, 1000.0},
    {"ddq", 7, "rad/s^2", "joint acceleration (not reported by a Franka; generators and users)", false, false,
     &JointLog::ddq, 1e5},
    {"tau_J_d", 7, "N m", "desired link-side joint torque without gravity", false, false, &JointLog::tau_J_d, 1000.0},
    {"q_d", 7, "rad", "desired joint position", false, false, &JointLog::q_d, 10.0},
    {"dq_d", 7, "rad/s", "desired joint velocity", false, false, &JointLog::dq_d, 50.0},
    {"ddq_d", 7, "rad/s^2", "desired joint acceleration", false, false, &JointLog::ddq_d, 1e5},
    {"dtau_J", 7, "N m/s", "derivative of the measured joint torque", false, false, &JointLog::dtau_J, 1e7},
    {"tau_ext_hat_filtered", 7, "N m", "filtered external torque estimate (tau_J minus the model's torque)", false,
     false, &JointLog::tau_ext_hat_filtered, 1000.0},
    {"O_F_ext_hat_K", 6, "N, N m", "estimated external wrench on the stiffness frame K, base frame, force first",
     false, false, &JointLog::O_F_ext_hat_K, 1e6},
    {"O_T_EE", 16, "m (translation)", "measured end-effector pose in the base frame, 4x4 column-major", false, false,
     &JointLog::O_T_EE, 100.0},
    {"robot_mode", 1, "", "libfranka's RobotMode name (Idle, Move, Reflex, ...)", false, true, &JointLog::robot_mode},
    {"command_received", 1, "", "1 if the cycle applied a command of the controller, 0 if not", false, false,
     &JointLog::command_received},
    {"control_command_success_rate", 1, "", "share of the last 100 commands received (0..1)", false, false,
     &JointLog::control_command_success_rate},
    {"current_errors", 1, "", "libfranka's error names of the current state as [name1|name2], [] without", false,
     true, &JointLog::current_errors},
}};

// Columns of a user's own start with this prefix (docs/joint-log.md: why `x_`).
inline constexpr std::string_view kExtensionPrefix = "x_";

// The CSV column name of element `index` (0-based) of a group: name1..nameN, or name when the
// width is 1.
std::string column_name(const ColumnGroup& group, int index);

// Sizes a CSV joint log may not exceed, so that a corrupt or hostile file is refused at once, in
// time linear in what was read, with a message of bounded length: a column name of the schema is
// at most 30 bytes and a number's shortest form at most 24; current_errors with all 41 libfranka
// errors about 1.3 kB; the widest row CSP writes about 2.5 kB.
inline constexpr std::size_t kMaxColumnNameBytes = 256;   // a column name, users' own x_ names too
inline constexpr std::size_t kMaxFieldBytes = 4096;       // one value's text
inline constexpr std::size_t kMaxLineBytes = 1 << 20;     // one line: 400 times the widest row

// Reads a CSV joint log. Throws JointLogError (file, line, column, what was expected) for a missing,
// unreadable or non-regular file (a directory or FIFO is refused, not waited on), an unknown
// column (with "did you mean" when the name is close to a known one), a duplicate or missing
// column, a field that is not a finite number or is beyond its group's physical bound
// (ColumnGroup::limit), a wrong number of fields, time not increasing, fewer than 2 rows, and a
// line, column name or field longer than the bounds above. Input quoted in a message is shortened
// (quote_input).
JointLog read_joint_log_csv(const std::string& path);

// Writes the groups present in `log` (and its extensions) in schema order.
void write_joint_log_csv(const std::string& path, const JointLog& log);

// Writes a CSV joint log row by row (the emulator's per-cycle log): the header at construction,
// one row per write_row. The columns are the groups present in `layout` and its extensions.
// Each row reaches the file when it is written (one write per row). A write error (disk full, a
// file size limit) throws JointLogError naming the file and the system's reason; the file then
// ends at its last complete row (nothing written before is lost) and the writer writes no more:
// write_row and flush throw the same error again.
class JointLogCsvWriter {
 public:
  // Throws JointLogError if `path` is no file to write (output_file_problem) or cannot be opened.
  JointLogCsvWriter(const std::string& path, const JointLog& layout);
  ~JointLogCsvWriter();   // closes, without throwing
  JointLogCsvWriter(const JointLogCsvWriter&) = delete;
  JointLogCsvWriter& operator=(const JointLogCsvWriter&) = delete;

  // Writes row `row` of `log`, which must have the layout's groups.
  void write_row(const JointLog& log, std::size_t row);
  void flush();
  const std::string& path() const { return path_; }

 private:
  static constexpr std::size_t kRowBytes = 1 << 13;   // reserved for a row (the widest CSP writes: 2.5 kB)

  void write_out();   // the buffer to the file
  [[noreturn]] void fail_write(int error, std::size_t written);

  std::string path_;
  int fd_ = -1;
  uint64_t complete_bytes_ = 0;   // bytes of whole lines in the file
  std::vector<const ColumnGroup*> groups_;
  std::size_t extensions_ = 0;
  std::string buffer_;            // the line being written
  std::string failure_;           // the write error, once there was one
};

// Input quoted in a message: `text` between backticks, shortened to its first `max_bytes` bytes
// followed by "... (N bytes)" when longer, control characters as \xNN, so that a message stays one
// line of bounded length whatever the input (a 10 MB column name).
std::string quote_input(std::string_view text, std::size_t max_bytes = 64);

// Why `path` cannot be written as an output file, or empty: it is a directory, a device, FIFO or
// socket (a log must be a file), a /proc or /sys entry (/proc/self/mem is "regular" but no file),
// read-only, or its directory is missing or not writable. Touches nothing: a refused path, and any
// file already there, stay as they were.
std::string output_file_problem(const std::string& path);
// The same for a directory a command writes files into (created if missing): an existing path must
// be a writable directory, else its nearest existing parent must be one.
std::string output_directory_problem(const std::string& path);
// True if `a` and `b` name the same file: the same inode if both exist, else the same absolute
// path once symbolic links and `.`/`..` are resolved.
bool same_file(const std::string& a, const std::string& b);

// Checks a log built in memory (from an LCM log, a generator) by the rules the CSV reader enforces:
// every present group has one entry per row, numbers finite, t strictly increasing, at least 2
// rows. Throws JointLogError naming log.source, the row and its time.
void check_joint_log(const JointLog& log);

// The rows with t in [t_begin, t_end), every group and extension.
JointLog slice(const JointLog& log, double t_begin, double t_end);

// The numeric columns `log` has, in schema order then its extensions: each column's name (as in
// the CSV header) and its values, one per row. For readers that treat every column alike (csp view's
// plots, MCAP's joint states); text columns (robot_mode, current_errors) are left out.
struct NumericColumn {
  std::string name;
  std::vector<double> values;
};
std::vector<NumericColumn> numeric_columns(const JointLog& log);

// Appends the rows of `part` (with the same groups and extensions as `log`, e.g. a slice of the
// same log) to `log`, their time moved back by `time_shift`.
void append_rows(JointLog& log, const JointLog& part, double time_shift);

}  // namespace csp
