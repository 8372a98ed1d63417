// A recorded run (a joint log: CSV, LCM or MCAP, or a plan's trajectory) as the page plays it: the
// frames for the 3D view at the display's rate, the events (reflexes and errors, where and when),
// and every numeric column for the plots.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/view/view_model.hpp"

namespace csp::view {

// The 3D view's frames are at most this far apart in the log's time [s] (100 Hz: smoother than
// the display's 60 Hz at normal speed, a tenth of a 1 kHz log's rows); a row where the robot's mode
// or errors change is always a frame.
inline constexpr double kFrameInterval = 0.01;

// A plot's series keeps at most this many points: for longer columns, each bucket's first, lowest,
// highest and last value in time order, so that a spike of one sample is still drawn.
inline constexpr std::size_t kMaxSeriesPoints = 4000;

struct Recording {
  std::string source;             // the file, for the page's title
  nlohmann::json frames;          // ViewModel::frame of the kept rows, in time order
  nlohmann::json events;          // [{t, mode, errors: [{name, joint}]}] where errors or the mode change
  std::vector<NumericColumn> columns;   // plot_columns of the log
  std::vector<double> t;          // the log's time, for the columns
};

Recording record(ViewModel& model, const JointLog& log);

// The columns the page can plot: the log's numeric columns (numeric_columns) and two it derives,
// so that recorded and live runs plot the same: tracking_error1..7 = q_d - q [rad] (with q_d) and
// force_norm = |O_F_ext_hat_K's force| [N] (with O_F_ext_hat_K).
std::vector<NumericColumn> plot_columns(const JointLog& log);

// The page's list of the recording's column names; and some columns as one plot's series
// ({t: [...], columns: {name: [...]}}, on common samples: the union of what decimate keeps of each,
// at most kMaxSeriesPoints per column). Throws std::out_of_range naming a column the recording
// does not have.
nlohmann::json column_names(const Recording& recording);
nlohmann::json series(const Recording& recording, const std::vector<std::string>& names);

// Indices of the samples a plot keeps of `n`: all when n <= max_points, else per bucket the first,
// the lowest, the highest and the last (in time order, no repeats).
std::vector<std::size_t> decimate(const std::vector<double>& values, std::size_t max_points);

}  // namespace csp::view
