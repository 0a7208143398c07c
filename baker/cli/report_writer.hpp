// The accuracy report of a job with a reference: every method layer against its reference layer.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/outputs.hpp"
#include "core/layers.hpp"
#include "job/manifest.hpp"

namespace hfbake {

struct MethodLayers {
  std::string stem, method;
  double seconds = 0;
  LayerSet layers;
};

struct ReportInputs {
  std::vector<MethodLayers> methods;
  LayerSet reference;
  double reference_seconds = 0;
};

struct ReportResult {
  nlohmann::json metrics_by_method = nlohmann::json::object();  // stem -> layer -> metrics
  std::vector<std::string> threshold_failures;                  // "p1.direct.rel_mae = 0.02 > 0.01"
  nlohmann::json report;                                        // the report.json document (for report.html)
};

// Compares, writes report.json into the stage, and evaluates the job's thresholds.
ReportResult write_report(const Job& job, const std::string& job_hash, const ReportInputs& inputs,
                          OutputStage& stage);

}  // namespace hfbake
