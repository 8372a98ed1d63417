#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "csp/io/svg_plot.hpp"

namespace csp::campaign {
namespace {

constexpr int kWorstRuns = 10;
constexpr std::size_t kMostDistinctValues = 12;   // a grid axis; more: equal-width bins
constexpr int kBins = 10;

double metric_of(const Outcome& outcome, const std::string& name) {
  for (const auto& [metric, value] : outcome.metrics)
    if (metric == name) return value;
  return NAN;
}

// One bin of an axis: the runs whose value lies in it.
struct Bin {
  double low = 0.0, high = 0.0;
  int runs = 0, failed = 0;
  std::map<std::string, int> gap_causes;   // how many of its runs csp gap's verdict named each cause in, when asked
  double centre() const { return 0.5 * (low + high); }
};

// Counts each cause a run's verdict names ("payload; joint_friction": one each), or `none`, or `not
// diagnosed` whatever the reason (results.csv has it): which cause comes with which value of an axis.
void count_causes(const std::string& verdict, std::map<std::string, int>& counts) {
  if (verdict.empty()) return;
  if (verdict.rfind("not diagnosed", 0) == 0) {
    ++counts["not diagnosed"];
    return;
  }
  for (std::size_t start = 0, end; start <= verdict.size(); start = end + 2) {
    end = std::min(verdict.find("; ", start), verdict.size());
    ++counts[verdict.substr(start, end - start)];
  }
}

// "payload 4, none 2": the causes, most often named first.
std::string cause_counts(const std::map<std::string, int>& counts) {
  std::vector<std::pair<std::string, int>> sorted(counts.begin(), counts.end());
  std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string out;
  for (const auto& [cause, runs] : sorted) out += format("%s%s %d", out.empty() ? "" : ", ", cause.c_str(), runs);
  return out;
}

// The axis's distinct values (a grid), or kBins equal-width bins over its range (a draw).
std::vector<Bin> bins_of(const std::vector<Row>& rows, std::size_t axis) {
  std::set<double> distinct;
  for (const Row& row : rows) distinct.insert(row.c->parameters[axis].second);
  std::vector<Bin> bins;
  if (distinct.size() <= kMostDistinctValues) {
    for (const double v : distinct) bins.push_back({v, v, 0, 0, {}});
  } else {
    const double low = *distinct.begin(), width = (*distinct.rbegin() - low) / kBins;
    for (int i = 0; i < kBins; ++i) bins.push_back({low + i * width, low + (i + 1) * width, 0, 0, {}});
  }
  for (const Row& row : rows) {
    const double v = row.c->parameters[axis].second;
    auto bin = std::find_if(bins.begin(), bins.end(), [&](const Bin& b) { return v >= b.low && v <= b.high; });
    ++bin->runs;
    bin->failed += row.outcome.failed ? 1 : 0;
    count_causes(row.outcome.gap_verdict, bin->gap_causes);
  }
  return bins;
}

// failure_rate_<axis>.svg: the failure rate per value (or bin) and every run's ranking metric.
std::string axis_figure(const CampaignDir& campaign, const std::vector<Row>& rows, std::size_t axis, const std::vector<Bin>& bins) {
  const std::string& parameter = campaign.campaign.axes[axis].parameter;
  PlotSeries rate{"failure rate", "#d62728", {}, {}, false};
  std::vector<std::string> scenarios;   // the scenario axis's names
  for (const Bin& bin : bins) {
    if (bin.runs == 0) continue;
    rate.x.push_back(bin.centre());
    rate.y.push_back(100.0 * bin.failed / bin.runs);
    if (parameter == "scenario") scenarios.push_back(scenario_name(campaign.campaign, bin.low));
  }
  rate.points = bins.front().low == bins.front().high;   // a grid's values: dots, not a line between them
  PlotSeries held{"held", "#2ca02c", {}, {}, true}, failed{"failed", "#d62728", {}, {}, true};
  for (const Row& row : rows) {
    const double value = metric_of(row.outcome, campaign.campaign.worst_by);
    if (std::isnan(value)) continue;
    PlotSeries& series = row.outcome.failed ? failed : held;
    series.x.push_back(row.c->parameters[axis].second);
    series.y.push_back(value);
  }
  // The scenario axis: a bar per scenario against 100 %.
  const PlotPanel rate_panel = scenarios.empty() ? PlotPanel{"failure rate", parameter, "runs failed [%]", {rate}, {}, 0.0}
                                                 : PlotPanel{"failure rate", "runs failed [%]", parameter, {rate}, scenarios, 100.0};
  return render_panels("campaign: failure rate against " + parameter,
                       {rate_panel,
                        {campaign.campaign.worst_by + " of each run", parameter, campaign.campaign.worst_by, {held, failed}, {}}},
                       2);
}

// region.svg: each run at its values of the first two axes, held or failed: where the controller holds.
std::string region_figure(const CampaignDir& campaign, const std::vector<Row>& rows) {
  const std::string& a = campaign.campaign.axes[0].parameter;
  const std::string& b = campaign.campaign.axes[1].parameter;
  PlotSeries held{"held", "#2ca02c", {}, {}, true}, failed{"failed", "#d62728", {}, {}, true};
  for (const Row& row : rows) {
    PlotSeries& series = row.outcome.failed ? failed : held;
    series.x.push_back(row.c->parameters[0].second);
    series.y.push_back(row.c->parameters[1].second);
  }
  return render_panels("campaign: where the controller holds", {{a + " vs " + b, a, b, {held, failed}, {}}}, 1);
}

std::string file_name(std::string parameter) {
  std::replace(parameter.begin(), parameter.end(), '.', '_');
  return parameter;
}

}  // namespace

void write_report(const CampaignDir& campaign, const std::vector<Row>& rows, int missing) {
  const std::string dir = campaign.dir + "/report";
  std::filesystem::create_directories(dir);
  const Campaign& file = campaign.campaign;
  int failed = 0;
  for (const Row& row : rows) failed += row.outcome.failed ? 1 : 0;

  std::string md = "# Campaign report\n\n";
  md += format("- campaign: `%s`\n", file.path.c_str());
  for (const std::string& scenario : file.scenarios) md += format("- base scenario: `%s`\n", scenario.c_str());
  md += format("- cases: %zu; run: %zu; missing: %d\n", campaign.cases.size(), rows.size(), missing);
  md += format("- failed: %d of %zu (%.1f %%): a reflex", failed, rows.size(), rows.empty() ? 0.0 : 100.0 * failed / rows.size());
  for (const auto& [metric, limit] : file.limits) md += format(", or %s > %g", metric.c_str(), limit);
  md += "\n";
  // The controller's compute time per cycle: the machine's, not the case's (it differs run to run).
  const Row* slowest = nullptr;
  for (const Row& row : rows)
    if (!slowest || row.outcome.controller_time_max_us > slowest->outcome.controller_time_max_us) slowest = &row;
  if (slowest)
    md += format("- the controller's compute time per cycle (this machine's, not deterministic): at most %.1f us (%s, p99 %.1f us)\n",
                 slowest->outcome.controller_time_max_us, slowest->c->id.c_str(), slowest->outcome.controller_time_p99_us);
  std::map<std::string, int> causes;
  for (const Row& row : rows) count_causes(row.outcome.gap_verdict, causes);
  if (!causes.empty()) md += "- the causes csp gap's verdicts name (docs/gap.md), in how many runs: " + cause_counts(causes) + "\n";
  md += "\n## Failure rate against each axis\n";
  for (std::size_t axis = 0; axis < file.axes.size() && !rows.empty(); ++axis) {
    const std::vector<Bin> bins = bins_of(rows, axis);
    const std::string figure = "failure_rate_" + file_name(file.axes[axis].parameter) + ".svg";
    write_text_file(dir + "/" + figure, axis_figure(campaign, rows, axis, bins));
    md += format("\n### `%s`\n\n![](%s)\n\n| value | runs | failed | rate |%s\n|---|---|---|---|%s\n",
                 file.axes[axis].parameter.c_str(), figure.c_str(), file.gap_verdict ? " csp gap's causes (runs) |" : "",
                 file.gap_verdict ? "---|" : "");
    for (const Bin& bin : bins) {
      const std::string value = file.axes[axis].parameter == "scenario" ? scenario_name(file, bin.low)
                                : bin.low == bin.high                   ? format("%g", bin.low)
                                                                        : format("%.4g to %.4g", bin.low, bin.high);
      md += format("| %s | %d | %d | %s |", value.c_str(), bin.runs, bin.failed,
                   bin.runs ? format("%.0f %%", 100.0 * bin.failed / bin.runs).c_str() : "-");
      if (file.gap_verdict) md += format(" %s |", cause_counts(bin.gap_causes).c_str());
      md += "\n";
    }
  }
  if (file.axes.size() >= 2 && !rows.empty()) {
    write_text_file(dir + "/region.svg", region_figure(campaign, rows));
    md += "\n## Where the controller holds (the first two axes)\n\n![](region.svg)\n";
  }

  // The worst runs: by the ranking metric, largest first (a run without it last).
  std::vector<const Row*> worst;
  for (const Row& row : rows) worst.push_back(&row);
  std::stable_sort(worst.begin(), worst.end(), [&](const Row* x, const Row* y) {
    const double a = metric_of(x->outcome, file.worst_by), b = metric_of(y->outcome, file.worst_by);
    if (x->outcome.failed != y->outcome.failed) return x->outcome.failed;
    return !std::isnan(a) && (std::isnan(b) || a > b);
  });
  md += format("\n## The worst runs (failed first, then by %s)\n\n| id | parameters | %s | failure |\n|---|---|---|---|\n",
               file.worst_by.c_str(), file.worst_by.c_str());
  for (std::size_t i = 0; i < worst.size() && i < kWorstRuns; ++i) {
    std::string parameters;
    for (const auto& [name, value] : worst[i]->c->parameters) {
      const std::string shown = name == "scenario" ? scenario_name(file, value) : format("%.6g", value);
      parameters += format("%s%s = %s", parameters.empty() ? "" : ", ", name.c_str(), shown.c_str());
    }
    md += format("| %s | %s | %.6g | %s |\n", worst[i]->c->id.c_str(), parameters.c_str(),
                 metric_of(worst[i]->outcome, file.worst_by), worst[i]->outcome.failure.c_str());
  }
  write_text_file(dir + "/summary.md", md);
}

}  // namespace csp::campaign
