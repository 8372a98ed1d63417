#include "csp/view/recording.hpp"

#include <algorithm>
#include <stdexcept>

namespace csp::view {

using nlohmann::json;

Recording record(ViewModel& model, const JointLog& log) {
  Recording recording;
  recording.source = log.source;
  recording.frames = json::array();
  recording.events = json::array();
  double last_frame_t = -1e300;
  for (std::size_t row = 0; row < log.size(); ++row) {
    const bool mode_changed = !log.robot_mode.empty() && row > 0 && log.robot_mode[row] != log.robot_mode[row - 1];
    const bool errors_changed =
        !log.current_errors.empty() && (row == 0 ? log.current_errors[row] != "[]" : log.current_errors[row] != log.current_errors[row - 1]);
    const bool last = row + 1 == log.size();
    if (!(mode_changed || errors_changed || last || log.t[row] - last_frame_t >= kFrameInterval - 1e-9)) continue;
    json frame = model.frame(log, row);
    if (mode_changed || (errors_changed && frame.contains("errors"))) {
      json event = {{"t", log.t[row]}};
      if (frame.contains("mode")) event["mode"] = frame["mode"];
      event["errors"] = frame.contains("errors") ? frame["errors"] : json::array();
      recording.events.push_back(std::move(event));
    }
    recording.frames.push_back(std::move(frame));
    last_frame_t = log.t[row];
  }
  recording.columns = plot_columns(log);
  recording.t = log.t;
  return recording;
}

json column_names(const Recording& recording) {
  json names = json::array();
  for (const NumericColumn& column : recording.columns) names.push_back(column.name);
  return names;
}

std::vector<std::size_t> decimate(const std::vector<double>& values, std::size_t max_points) {
  std::vector<std::size_t> kept;
  if (values.size() <= max_points || max_points < 4) {
    for (std::size_t i = 0; i < values.size(); ++i) kept.push_back(i);
    return kept;
  }
  const std::size_t buckets = max_points / 4;
  for (std::size_t b = 0; b < buckets; ++b) {
    const std::size_t begin = b * values.size() / buckets, end = (b + 1) * values.size() / buckets;
    const auto [low, high] = std::minmax_element(values.begin() + static_cast<std::ptrdiff_t>(begin),
                                                 values.begin() + static_cast<std::ptrdiff_t>(end));
    std::size_t picks[] = {begin, static_cast<std::size_t>(low - values.begin()),
                           static_cast<std::size_t>(high - values.begin()), end - 1};
    std::sort(std::begin(picks), std::end(picks));
    for (const std::size_t i : picks)
      if (kept.empty() || kept.back() != i) kept.push_back(i);
  }
  return kept;
}

json series(const Recording& recording, const std::vector<std::string>& names) {
  std::vector<const NumericColumn*> columns;
  std::vector<std::size_t> kept;
  for (const std::string& name : names) {
    const auto column = std::find_if(recording.columns.begin(), recording.columns.end(),
                                     [&](const NumericColumn& c) { return c.name == name; });
    if (column == recording.columns.end()) throw std::out_of_range("no column " + name + " in " + recording.source);
    columns.push_back(&*column);
    const std::vector<std::size_t> picks = decimate(column->values, kMaxSeriesPoints);
    kept.insert(kept.end(), picks.begin(), picks.end());
  }
  std::sort(kept.begin(), kept.end());
  kept.erase(std::unique(kept.begin(), kept.end()), kept.end());
  json t = json::array(), values = json::object();
  for (const std::size_t i : kept) t.push_back(recording.t[i]);
  for (const NumericColumn* column : columns) {
    json& v = values[column->name] = json::array();
    for (const std::size_t i : kept) v.push_back(column->values[i]);
  }
  return {{"t", t}, {"columns", values}};
}

std::vector<NumericColumn> plot_columns(const JointLog& log) {
  std::vector<NumericColumn> columns = numeric_columns(log);
  if (!log.q_d.empty()) {
    for (int j = 0; j < kNumJoints; ++j) {
      NumericColumn& error = columns.emplace_back(NumericColumn{"tracking_error" + std::to_string(j + 1), {}});
      for (std::size_t k = 0; k < log.size(); ++k) error.values.push_back(log.q_d[k][j] - log.q[k][j]);
    }
  }
  if (!log.O_F_ext_hat_K.empty()) {
    NumericColumn& norm = columns.emplace_back(NumericColumn{"force_norm", {}});
    for (const Vector6& wrench : log.O_F_ext_hat_K) norm.values.push_back(wrench.head<3>().norm());
  }
  return columns;
}

}  // namespace csp::view
