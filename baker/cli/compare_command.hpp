// `hfbake compare NEW BASELINE`: a new report.json against a baseline (or every report.json under a
// folder, e.g. a suite's output, against the same relative paths under a baseline folder).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hfbake {

struct CompareOptions {
  std::filesystem::path now, baseline;
  std::vector<std::string> tolerances;  // "METRIC=REL[,ABS]", added to / replacing the default checked set
  bool all = false;                     // list every checked metric, not only changes
  bool update_baseline = false;         // after comparing, copy NEW over BASELINE (deliberately)
  // A baseline that is a report of another job (report/baseline_compare.hpp: job_differences) is refused
  // (exit 2, one line per such baseline) unless this is set; then the differences are printed as a note.
  bool allow_different_job = false;
  std::optional<std::filesystem::path> json;  // write the comparison as JSON
  bool quiet = false;
};

// What a comparison found: the --json document's "comparisons" and "regression", the reports refused as
// another job's (one line each, "<baseline>: <why> (...)": then nothing was written or updated), the text
// the command prints (tables, notes) and whether the baseline was updated.
struct CompareResult {
  nlohmann::json comparisons = nlohmann::json::array();
  bool regression = false;
  std::vector<std::string> refusals;
  std::string text;
  bool baseline_updated = false;
};

// The comparison (and --json, --update-baseline) without printing. Throws InputError for bad input
// (a --tolerance, a missing file, a report that is not one), std::filesystem_error for an I/O failure.
CompareResult compare_reports(const CompareOptions& options);

// 0 nothing regressed (or the baseline was updated), 1 a regression, 2 bad input (a baseline of another
// job included: then nothing is updated).
int run_compare(const CompareOptions& options);

}  // namespace hfbake
