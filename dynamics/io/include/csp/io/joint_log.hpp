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
#include <fstream>
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
};

// The schema, in the column order writers use: the real Panda log's t, q, dq, tau_J first, then
// the optional groups as `csp emulate --log` has always written them.
inline constexpr std::array<ColumnGroup, 17> kJointLogSchema = {{
    {"t", 1, "s", "time since the robot started (1 ms steps on a Franka)", true, false, &JointLog::t},
    {"q", 7, "rad", "measured joint position", true, false, &JointLog::q},
    {"dq", 7, "rad/s", "measured joint velocity", true, false, &JointLog::dq},
    {"tau_J", 7, "N m", "measured link-side joint torque, gravity included", true, false, &JointLog::tau_J},
    {"ddq", 7, "rad/s^2", "joint acceleration (not reported by a Franka; generators and users)", false, false,
     &JointLog::ddq},
    {"tau_J_d", 7, "N m", "desired link-side joint torque without gravity", false, false, &JointLog::tau_J_d},
    {"q_d", 7, "rad", "desired joint position", false, false, &JointLog::q_d},
    {"dq_d", 7, "rad/s", "desired joint velocity", false, false, &JointLog::dq_d},
    {"ddq_d", 7, "rad/s^2", "desired joint acceleration", false, false, &JointLog::ddq_d},
    {"dtau_J", 7, "N m/s", "derivative of the measured joint torque", false, false, &JointLog::dtau_J},
    {"tau_ext_hat_filtered", 7, "N m", "filtered external torque estimate (tau_J minus the model's torque)", false,
     false, &JointLog::tau_ext_hat_filtered},
    {"O_F_ext_hat_K", 6, "N, N m", "estimated external wrench on the stiffness frame K, base frame, force first",
     false, false, &JointLog::O_F_ext_hat_K},
    {"O_T_EE", 16, "m (translation)", "measured end-effector pose in the base frame, 4x4 column-major", false, false,
     &JointLog::O_T_EE},
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

// Reads a CSV joint log. Throws JointLogError (file, line, column, what was expected) for a missing,
// unreadable or non-regular file (a directory or FIFO is refused, not waited on), an unknown
// column (with "did you mean" when the name is close to a known one), a duplicate or missing
// column, a field that is not a finite number, a wrong number of fields, time not increasing,
// fewer than 2 rows.
JointLog read_joint_log_csv(const std::string& path);

// Writes the groups present in `log` (and its extensions) in schema order.
void write_joint_log_csv(const std::string& path, const JointLog& log);

// Writes a CSV joint log row by row (the emulator's per-cycle log): the header at construction,
// one row per write_row. The columns are the groups present in `layout` and its extensions.
class JointLogCsvWriter {
 public:
  JointLogCsvWriter(const std::string& path, const JointLog& layout);   // throws JointLogError
  // Writes row `row` of `log`, which must have the layout's groups.
  void write_row(const JointLog& log, std::size_t row);
  void flush();
  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail_write();

  std::string path_;
  std::ofstream out_;
  std::vector<const ColumnGroup*> groups_;
  std::size_t extensions_ = 0;
  std::string line_;
};

// Checks a log built in memory (from an LCM log, a generator) by the rules the CSV reader enforces:
// every present group has one entry per row, numbers finite, t strictly increasing, at least 2
// rows. Throws JointLogError naming log.source, the row and its time.
void check_joint_log(const JointLog& log);

// The rows with t in [t_begin, t_end), every group and extension.
JointLog slice(const JointLog& log, double t_begin, double t_end);

// Appends the rows of `part` (with the same groups and extensions as `log`, e.g. a slice of the
// same log) to `log`, their time moved back by `time_shift`.
void append_rows(JointLog& log, const JointLog& part, double time_shift);

}  // namespace csp
