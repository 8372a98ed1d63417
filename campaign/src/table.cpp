#include "csp/campaign/table.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "csp/io/svg_plot.hpp"
#include "report.hpp"

namespace csp::campaign {
namespace {

// A CSV field (RFC 4180): quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// Exact: a double written with 17 significant digits reads back as itself. Empty: did not happen (NaN).
std::string csv_number(double value) { return std::isnan(value) ? std::string() : format("%.17g", value); }

// The fields joined by commas, a line.
std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (const std::string& field : fields) {
    if (!line.empty()) line += ',';
    line += field;
  }
  line += '\n';
  return line;
}

}  // namespace

Collected collect_results(const CampaignDir& campaign) {
  Collected collected;
  std::vector<Row> rows;
  for (const Case& c : campaign.cases) {
    const std::string path = campaign.dir + "/runs/" + c.id + ".json";
    if (!std::filesystem::exists(path)) {
      ++collected.missing;
      continue;
    }
    rows.push_back({&c, read_outcome_json(path)});
    collected.failed += rows.back().outcome.failed ? 1 : 0;
  }
  collected.rows = static_cast<int>(rows.size());

  // The header from the campaign (its axes) and the first row's metrics (every row has the same).
  std::vector<std::string> header{"id", "case_seed"};
  for (const Axis& axis : campaign.campaign.axes) header.push_back(csv_field(axis.parameter));
  header.insert(header.end(), {"reflex", "failed"});
  // The kept metrics (all unless the file chose), by their index in every row.
  const auto& kept = campaign.campaign.kept;
  std::vector<std::size_t> columns;
  if (!rows.empty()) {
    const auto& metrics = rows.front().outcome.metrics;
    for (std::size_t i = 0; i < metrics.size(); ++i) {
      if (!kept.empty() && std::find(kept.begin(), kept.end(), metrics[i].first) == kept.end()) continue;
      columns.push_back(i);
      header.push_back(metrics[i].first);
    }
  }
  header.insert(header.end(), {"reflex_errors", "failure"});
  const bool gap = campaign.campaign.gap_verdict;
  if (gap) header.push_back("gap_verdict");
  // Last: the timing, the columns that are not deterministic.
  header.insert(header.end(), {"controller_time_p99_us", "controller_time_max_us", "wall_time_s"});
  std::string csv = csv_line(header);
  for (const Row& row : rows) {
    const Outcome& o = row.outcome;
    if (o.metrics.size() != rows.front().outcome.metrics.size())
      throw std::runtime_error(campaign.dir + "/runs/" + o.id + ".json: other metrics than the other runs'");
    std::vector<std::string> fields{row.c->id, std::to_string(row.c->seed)};
    for (const auto& [name, value] : row.c->parameters)
      fields.push_back(name == "scenario" ? csv_field(scenario_name(campaign.campaign, value)) : csv_number(value));
    fields.insert(fields.end(), {o.reflex ? "1" : "0", o.failed ? "1" : "0"});
    for (const std::size_t i : columns) fields.push_back(csv_number(o.metrics[i].second));
    fields.insert(fields.end(), {csv_field(o.reflex_errors), csv_field(o.failure)});
    if (gap) fields.push_back(csv_field(o.gap_verdict));
    fields.insert(fields.end(), {format("%.1f", o.controller_time_p99_us), format("%.1f", o.controller_time_max_us),
                                 format("%.6f", o.wall_time_s)});
    csv += csv_line(fields);
  }
  write_text_file(campaign.dir + "/results.csv", csv);
  write_report(campaign, rows, collected.missing);
  return collected;
}

}  // namespace csp::campaign
