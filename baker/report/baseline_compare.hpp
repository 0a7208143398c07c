// Baselines: a new report.json against a previous one (`hfbake compare NEW BASELINE`), metric by metric.
// A checked metric regresses when it gets worse by more than its tolerance:
//   lower-is-better metrics: new > old + max(abs, rel * |old|)
//   psnr (higher is better):  new < old - max(abs, rel * |old|)
// and improves when it gets better by more than the same margin. A checked metric that the baseline has
// and the new report lacks (a method, layer or metric that disappeared) is a regression too; what only
// the new report has is listed as new. Metrics that are not checked are listed for information only.
// The default checked set and tolerances are the job's report.baseline rule (report_document.hpp).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hfbake {

struct MetricTolerance {
  double rel = 0, abs = 0;
};

struct BaselineOptions {
  std::map<std::string, MetricTolerance> checked;  // metric -> tolerance
  // mae, rmse, excess_rmse with kBaselineRelTolerance / kBaselineAbsTolerance.
  static BaselineOptions defaults();
};

// Parses "metric=rel" or "metric=rel,abs" (e.g. "max=0.1,1e-4") into `options`; "" or an error message.
std::string parse_tolerance(const std::string& text, BaselineOptions& options);

enum class MetricChange { same, improved, regressed, missing, added, info };
const char* metric_change_name(MetricChange c);  // "same", "improved", "REGRESSED", "MISSING", "new", "info"

struct MetricRow {
  std::string stem, layer, metric;  // key: <stem>.<layer>.<metric>
  std::optional<double> now, was;
  MetricChange change = MetricChange::same;
  bool checked = false;
  MetricTolerance tolerance;
  std::string key() const { return stem + "." + layer + "." + metric; }
};

// A method parameter (or a method's name) that differs between the two reports, as recorded in
// /methods/<stem>/parameters: key "<stem>.<parameter>" (nested objects joined by '.'; arrays compared
// whole), or "<stem>.method". An absent side is nullopt (a key added, removed, or left to its default).
struct ParameterChange {
  std::string key;
  std::optional<nlohmann::json> now, was;
};

struct BaselineComparison {
  std::string label;  // e.g. the job's name; "" for a single comparison
  // Why the baseline is not a report of the same job (see job_differences); empty when it is.
  std::vector<std::string> job_differences;
  std::vector<ParameterChange> parameter_changes;  // of the stems both reports have
  std::vector<MetricRow> rows;
  int regressed = 0, improved = 0, missing = 0, added = 0;
  bool regression() const { return regressed + missing > 0; }
};

// What makes `baseline` a report of another job than `now`, one phrase per difference, "" parts never:
//   the job's name (/job/name), the field size (/size), the crop (/crop), the reference settings
//   (/reference/parameters, key by key), the scene as written (/job/scene: height, surface, environment,
//   lights, bounces, key by key) and, when the scene as written is the same, the bytes of its input files
//   (/job/scene_hash). What a document does not record (reports written before /job/scene existed) is not
//   compared. Empty: the same job, so its metrics are comparable.
std::vector<std::string> job_differences(const nlohmann::json& now, const nlohmann::json& baseline);

// The method parameters that changed between the two reports, for the stems both have, sorted by key.
std::vector<ParameterChange> parameter_changes(const nlohmann::json& now, const nlohmann::json& baseline);

// The one-line reason for refusing a baseline: "a report of another job: <difference>; <difference>".
std::string another_job_message(const std::vector<std::string>& differences);

// Fills job_differences and parameter_changes too (the caller decides whether a different job is refused).
// Throws std::invalid_argument when either document is not a report.json (no "methods" object, or a
// method without a "layers" object).
BaselineComparison compare_to_baseline(const nlohmann::json& now, const nlohmann::json& baseline,
                                       const BaselineOptions& options);

// A plain-text table for a terminal: the parameter changes, what regressed, went missing, improved or is new
// (with `all`, every checked row too), then a one-line verdict.
std::string comparison_table(const BaselineComparison& c, bool all);

// The comparison as JSON (for --json and the suite summary), with "job_differences" and
// "parameter_changes" ([{key, value, baseline}], an absent side left out).
nlohmann::json comparison_json(const BaselineComparison& c);

}  // namespace hfbake
