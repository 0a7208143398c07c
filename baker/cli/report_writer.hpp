// The accuracy report of a job with a reference: every method layer against its reference layer.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/outputs.hpp"
#include "core/layers.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"
#include "report/report_document.hpp"

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

// report.json's /job/scene: the job's height, surface, environment, lights and bounces as written, each input
// file's path replaced by "fnv1a:<hash of its bytes>". InputError if an input file cannot be read.
nlohmann::json job_scene(const Job& job);

// Reads a report.json (a baseline, or `hfbake compare`'s inputs): a regular JSON file within the job
// reader's bounds, checked against schemas/report.schema.json and report/report_document.hpp
// impossible_report_value. InputError naming the file and the field when it is not one as hfbake writes it (a
// negative mae, a metric that is text, a key missing, an rmse beyond any two floats' difference).
nlohmann::json read_report_file(const std::filesystem::path& file);

// Refuses (InputError at /report/baseline) a report.baseline that is a report of another job than the one
// this job's report will be (name, field size, crop, reference settings, scene: report/baseline_compare.hpp),
// before anything is baked. Does nothing for a job without a reference or a baseline.
void check_report_baseline(const Job& job, int width, int height);

// What limits the reach of an entry's layers, from its config: the falloff it wrote (none when it gave
// neither falloff nor radius), its weighting, and relief's search as the reference records it.
EntryReach entry_reach(const MethodConfig& config);

// Compares, writes report.json into the stage, and evaluates the job's thresholds.
ReportResult write_report(const Job& job, const std::string& job_hash, const ReportInputs& inputs,
                          OutputStage& stage);

}  // namespace hfbake
