// What happened to one job of a `bake` call: the input of the summary, the suite reports and JUnit XML.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hfbake {

enum class JobStatus { ok, threshold_failed, failed, invalid, cancelled };

inline const char* job_status_name(JobStatus s) {
  switch (s) {
    case JobStatus::ok:
      return "ok";
    case JobStatus::threshold_failed:
      return "regressed";
    case JobStatus::failed:
      return "failed";
    case JobStatus::invalid:
      return "invalid";
    case JobStatus::cancelled:
      return "interrupted";
  }
  return "?";
}

struct JobOutcome {
  std::string file, name;
  JobStatus status = JobStatus::ok;
  std::vector<std::string> errors;
  // What the bake warned about, one line each, "<file>: <what>": the job file for its heights
  // (heights_warning), an output file for its values (the Python module issues them as Python warnings).
  std::vector<std::string> warnings;
  std::vector<std::filesystem::path> outputs;
  nlohmann::json methods = nlohmann::json::object();  // stem -> {method, seconds, metrics, cache}
  // The report's comparison with the job's report.baseline ({file, rel_tolerance, abs_tolerance,
  // regressions}: report.schema.json's "baseline"); null when the job names no baseline or wrote no report.
  nlohmann::json baseline;
  double seconds = 0;
};

}  // namespace hfbake
