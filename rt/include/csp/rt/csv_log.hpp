// The per-cycle CSV log of `csp emulate`: the column layout of the real Panda log
// (t, q1..q7, dq1..q7, tau_J1..tau_J7) followed by the other fields, so real and emulated data
// share one format. Numbers are written in their shortest exact form: the same run gives the
// same bytes. Rows are flushed when the log closes, also when a controller failure unwinds.
#pragma once

#include <fstream>
#include <string>

#include "csp/rt/control_loop.hpp"

namespace csp::rt {

class CsvLog {
 public:
  explicit CsvLog(const std::string& path);   // throws std::runtime_error if it cannot be written
  ~CsvLog();
  CsvLog(const CsvLog&) = delete;
  CsvLog& operator=(const CsvLog&) = delete;

  void write(const RobotState& state, const CycleInfo& cycle);
  uint64_t rows() const { return rows_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  std::string line_;
  uint64_t rows_ = 0;
};

}  // namespace csp::rt
