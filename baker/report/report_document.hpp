// report.json: every method layer against the reference layer of the same name, timings, parameters, and
// the job's thresholds and baseline turned into pass / fail. Pure data in, JSON out (no file I/O here).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/layers.hpp"
#include "report/compare.hpp"

namespace hfbake {

// What limits the reach of an entry's layers (core/layers.hpp LayerReach), from its typed config: the report
// scores a limited layer only against a reference layer limited the same way.
struct EntryReach {
  std::string falloff = "none";  // its obscurance's and bent normal's falloff (falloff_kind_name), and radius
  double radius = 0;
  bool cosine_weighted = true;  // its obscurance's weighting
  // Its search settings as the reference records those it traced relief's layers with
  // (reference/relief_reference.hpp relief_reference_record); null: none.
  nlohmann::json search;
};

struct ReportMethodInput {
  std::string stem, method;  // output stem ("p1", "p1-2") and method name
  double seconds = 0;
  nlohmann::json parameters;         // the entry's resolved parameters, written to report.json
  const LayerSet* layers = nullptr;  // not owned
  EntryReach reach = {};
};

struct ReportSpec {
  std::string hfbake_version, job_name, job_file, job_hash;
  // What identifies the job's scene for baseline comparisons (report.json /job/scene; null: not written).
  nlohmann::json job_scene;
  nlohmann::json reference_parameters = nlohmann::json::object();
  double reference_seconds = 0;
  int crop = 0;
  nlohmann::json thresholds = nlohmann::json::object();  // "<stem>.<layer>.<metric>": limit
  std::optional<nlohmann::json> baseline;                // a previous report.json, when the job names one
  std::string baseline_file;                             // for messages
};

// Baseline regression rule: a metric in kBaselineMetrics regresses when
//   new > old * (1 + kBaselineRelTolerance) + kBaselineAbsTolerance.
inline constexpr double kBaselineRelTolerance = 0.05;
inline constexpr double kBaselineAbsTolerance = 1e-5;
inline const char* const kBaselineMetrics[] = {"mae", "rmse", "excess_rmse"};

struct ReportOutcome {
  nlohmann::json doc;                                           // report.json
  nlohmann::json metrics_by_method = nlohmann::json::object();  // stem -> layer -> metrics
  std::vector<std::string> failures;                            // one line each
};

// Compares every method layer that has a reference layer (same name, same channel count; "<x>_stderr"
// layers are the reference's noise, never compared), evaluates thresholds (a maximum for every metric but
// psnr, which is a minimum; bias is compared by its magnitude; a threshold naming a method, layer or
// metric the report does not have fails, so a typo cannot pass silently) and the baseline.
ReportOutcome build_report(const ReportSpec& spec, const std::vector<ReportMethodInput>& methods,
                           const LayerSet& reference);

// Metrics as JSON (absent optional metrics are left out).
nlohmann::json metrics_json(const LayerMetrics& m);

// The largest difference of two float32 values: no error, bias or mean of a report lies beyond it.
inline constexpr double kMaxReportMagnitude = 2.0 * 3.4028234663852886e38;

// A value of a report.json (valid against schemas/report.schema.json) that no bake writes: an error metric,
// bias, mean or reference noise beyond kMaxReportMagnitude in magnitude, an angle beyond 180 degrees. Its
// JSON pointer and the rule it breaks, or nullopt.
std::optional<std::pair<std::string, std::string>> impossible_report_value(const nlohmann::json& report);

}  // namespace hfbake
