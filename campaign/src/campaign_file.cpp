#include "csp/campaign/campaign_file.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "csp/campaign/cases.hpp"
#include "csp/campaign/runner.hpp"
#include "csp/io/yaml_field.hpp"

namespace csp::campaign {
namespace {

// A base scenario: a path relative to the campaign file, or a shipped scenario's name
// (configs/scenarios/: default, medical/ultrasound_abdomen_scan).
std::string base_scenario(const Field& field, const std::string& campaign_path) {
  const std::string text = field.text();
  std::filesystem::path path = text;
  if (path.is_relative()) path = std::filesystem::path(campaign_path).parent_path() / path;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error) && path.extension() != ".yaml") path = rt::shipped_scenario_path(text);
  if (!std::filesystem::is_regular_file(path, error))
    field.fail("a scenario file or a shipped scenario's name (" + path.string() + " not found)");
  return std::filesystem::absolute(path).lexically_normal().string();
}

// `gap: {verdict: FILE, cause: NAME, value: KEY, joint: N}`: the 95 % interval a `csp gap --json`
// verdict gives one of its causes' fitted values (verdict.params.NAME.KEY_interval, joint N's for a
// per-joint value): the range the real robot's parameter lies in, as far as its log tells.
void read_gap_interval(const Field& field, Axis& axis) {
  field.allow_only({"verdict", "cause", "value", "joint"});
  std::filesystem::path path = field["verdict"].text();
  if (path.is_relative()) path = std::filesystem::path(field.file()).parent_path() / path;
  std::ifstream in(path);
  if (!in) field["verdict"].fail("a `csp gap --json` verdict file (" + path.string() + " cannot be read)");
  const nlohmann::json verdict = nlohmann::json::parse(in, nullptr, false);
  if (verdict.is_discarded() || !verdict.contains("verdict") || !verdict["verdict"].contains("params"))
    field["verdict"].fail("a `csp gap --json` verdict file (" + path.string() + " has no verdict.params)");
  const std::string cause = field["cause"].text(), value = field["value"].text();
  const nlohmann::json& params = verdict["verdict"]["params"];
  if (!params.contains(cause) || !params[cause].is_object()) field["cause"].fail("a cause of the verdict (" + path.string() + ")");
  const std::string key = value + "_interval";
  if (!params[cause].contains(key)) field["value"].fail("a fitted value of " + cause + " with an interval (no " + key + ")");
  nlohmann::json interval = params[cause][key];
  if (field.has("joint")) {
    const int64_t joint = field["joint"].whole_number(1, kNumJoints);
    if (!interval.is_array() || interval.size() != kNumJoints) field["joint"].fail("no joint: " + key + " is not per joint");
    interval = interval[static_cast<std::size_t>(joint - 1)];
  }
  if (!interval.is_array() || interval.size() != 2 || !interval[0].is_number() || !interval[1].is_number())
    field["value"].fail("a value whose interval is [low, high] (" + key + ": " + interval.dump() + "; per joint: give joint)");
  axis.kind = Axis::Kind::kUniform;
  axis.low = interval[0].get<double>();
  axis.high = interval[1].get<double>();
  if (!(axis.low < axis.high)) field.fail("an interval with low < high (" + key + ": " + interval.dump() + ")");
}

Axis read_axis(const Field& field) {
  field.allow_only({"parameter", "values", "uniform", "normal", "gap"});
  Axis axis;
  axis.parameter = field["parameter"].text();
  const int ways = int(field.has("values")) + int(field.has("uniform")) + int(field.has("normal")) + int(field.has("gap"));
  if (ways != 1)
    field.fail("exactly one of values (a grid), uniform [low, high], normal {mean, sd, low, high} or gap {verdict, cause, value, joint}");
  if (field.has("gap")) {
    read_gap_interval(field["gap"], axis);
  } else if (field.has("values")) {
    const Field values = field["values"];
    if (values.sequence_size() == 0) values.fail("a list of at least one number");
    for (std::size_t i = 0; i < values.sequence_size(); ++i) axis.values.push_back(values[i].number());
  } else if (field.has("uniform")) {
    const Field range = field["uniform"];
    if (range.sequence_size() != 2) range.fail("[low, high]");
    axis.kind = Axis::Kind::kUniform;
    axis.low = range[0].number();
    axis.high = range[1].number();
    if (!(axis.low < axis.high)) range.fail("[low, high] with low < high");
  } else {
    const Field normal = field["normal"];
    normal.allow_only({"mean", "sd", "low", "high"});
    axis.kind = Axis::Kind::kNormal;
    axis.mean = normal["mean"].number();
    axis.sd = positive(normal["sd"]);
    axis.low = normal["low"].number();
    axis.high = normal["high"].number();
    if (!(axis.low <= axis.mean && axis.mean <= axis.high) || axis.low == axis.high)
      normal.fail("low <= mean <= high with low < high (the draws are clipped to [low, high])");
  }
  return axis;
}

// A value the axis takes, to check that its parameter applies to the base scenario.
double some_value(const Axis& axis) {
  return axis.kind == Axis::Kind::kValues ? axis.values.front() : axis.kind == Axis::Kind::kUniform ? axis.low : axis.mean;
}

}  // namespace

// `{parameter: scenario, values: [FILE or NAME, ...]}`: the base scenarios, as a grid axis of their indices.
Axis read_scenario_axis(const Field& field, Campaign& campaign) {
  field.allow_only({"parameter", "values"});
  const Field values = field["values"];
  if (values.sequence_size() == 0) values.fail("a list of scenario files or shipped scenarios' names");
  Axis axis;
  axis.parameter = "scenario";
  for (std::size_t i = 0; i < values.sequence_size(); ++i) {
    campaign.scenarios.push_back(base_scenario(values[i], field.file()));
    campaign.scenario_names.push_back(values[i].text());
    axis.values.push_back(static_cast<double>(i));
  }
  return axis;
}

Campaign load_campaign(const std::string& path) {
  const YAML::Node root = load_yaml_file(path, "campaign file");
  const Field file(root, path, "");
  file.allow_only({"name", "description", "base", "duration", "seed", "runs", "axes", "fail_if", "worst_by", "metrics", "gap_verdict"});
  Campaign campaign;
  campaign.path = path;
  const Field axes = file["axes"];
  std::vector<std::size_t> scenario_axes;
  for (std::size_t i = 0; i < axes.sequence_size(); ++i)
    if (axes[i].has("parameter") && axes[i]["parameter"].text() == "scenario") scenario_axes.push_back(i);
  if (scenario_axes.size() > 1) axes[scenario_axes[1]]["parameter"].fail("one `scenario` axis");
  if (scenario_axes.empty()) campaign.scenarios.push_back(base_scenario(file["base"], path));
  else if (file.has("base")) file["base"].fail("no base with a `scenario` axis (its values are the base scenarios)");
  if (file.has("duration")) {
    campaign.duration = positive(file["duration"]);
    if (*campaign.duration > rt::kMaxDuration) file["duration"].fail("at most a year of seconds");
  }
  if (file.has("seed")) campaign.seed = static_cast<uint64_t>(file["seed"].whole_number(0, int64_t{1} << 53));
  if (file.has("gap_verdict")) campaign.gap_verdict = file["gap_verdict"].boolean();
  if (file.has("runs")) campaign.runs = static_cast<int>(file["runs"].whole_number(1, 1'000'000));

  // Every parameter is applied once to each base scenario: an unknown name is this file's error.
  std::vector<rt::Scenario> bases;
  if (!scenario_axes.empty()) campaign.axes.push_back(read_scenario_axis(axes[scenario_axes[0]], campaign));
  for (const std::string& scenario : campaign.scenarios) bases.push_back(rt::load_scenario(scenario));
  std::set<std::string> seen{"scenario"};
  std::size_t grid = campaign.scenarios.size();
  for (std::size_t i = 0; i < axes.sequence_size(); ++i) {
    if (!scenario_axes.empty() && i == scenario_axes[0]) continue;
    const Axis axis = read_axis(axes[i]);
    if (!seen.insert(axis.parameter).second) axes[i]["parameter"].fail("a parameter not swept by another axis");
    for (rt::Scenario& scenario : bases) {
      try {
        apply_parameter(scenario, axis.parameter, some_value(axis));
      } catch (const std::invalid_argument& e) {
        axes[i]["parameter"].fail(e.what());
      }
    }
    if (axis.kind == Axis::Kind::kValues) grid *= axis.values.size();
    if (grid * static_cast<std::size_t>(campaign.runs) > 1'000'000) axes[i].fail("at most a million cases in all");
    campaign.axes.push_back(axis);
  }

  // One table: every base scenario's runs measure the same (all with the same kind of scene task, or none).
  const std::vector<std::string> metrics = metric_names(bases.front(), campaign.gap_verdict);
  for (std::size_t i = 1; i < bases.size(); ++i)
    if (metric_names(bases[i], campaign.gap_verdict) != metrics)
      axes[scenario_axes[0]]["values"][i].fail("a scenario whose runs have the metrics of the first (the same kind of task, or none)");
  auto check_metric = [&](const Field& field, const std::string& name) {
    if (std::find(metrics.begin(), metrics.end(), name) != metrics.end()) return;
    std::string list;
    for (const std::string& m : metrics) list += (list.empty() ? "" : ", ") + m;
    field.fail("a metric of this scenario (" + list + ")");
  };
  if (file.has("fail_if")) {
    const Field limits = file["fail_if"];
    for (const std::string& name : limits.keys()) {
      check_metric(limits[name], name);
      campaign.limits[name] = limits[name].number();
    }
  }
  if (file.has("metrics")) {
    const Field kept = file["metrics"];
    for (std::size_t i = 0; i < kept.sequence_size(); ++i) {
      check_metric(kept[i], kept[i].text());
      campaign.kept.push_back(kept[i].text());
    }
  }
  campaign.worst_by = metrics.front();
  if (file.has("worst_by")) {
    campaign.worst_by = file["worst_by"].text();
    check_metric(file["worst_by"], campaign.worst_by);
  }
  return campaign;
}

}  // namespace csp::campaign
