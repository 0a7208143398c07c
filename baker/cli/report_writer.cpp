// Glue between a baked job and report/report_document: reads the job's "report" options and the baseline
// file, builds report.json and stages it.
#include "cli/report_writer.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "cli/version.hpp"
#include "core/error.hpp"
#include "report/report_document.hpp"

namespace hfbake {

ReportResult write_report(const Job& job, const std::string& job_hash, const ReportInputs& inputs,
                          OutputStage& stage) {
  const nlohmann::json options = job.doc.value("report", nlohmann::json::object());
  ReportSpec spec;
  spec.hfbake_version = hfbake_version();
  spec.job_name = job.name;
  spec.job_file = job.file.string();
  spec.job_hash = job_hash;
  // Resolved: every default filled in (what the reference used).
  spec.reference_parameters = job.reference_resolved.is_object()
                                  ? job.reference_resolved
                                  : job.doc.value("reference", nlohmann::json::object());
  spec.reference_seconds = inputs.reference_seconds;
  spec.crop = options.value("crop", 0);
  spec.thresholds = options.value("thresholds", nlohmann::json::object());
  if (options.contains("baseline")) {
    const std::string written = options["baseline"].get<std::string>();
    const auto path = job.resolve(written);
    std::ifstream in(path);
    if (!in) throw InputError(job.file.string(), "/report/baseline", "cannot read " + path.string());
    std::stringstream ss;
    ss << in.rdbuf();
    try {
      spec.baseline = nlohmann::json::parse(ss.str());
    } catch (const nlohmann::json::exception& e) {
      throw InputError(job.file.string(), "/report/baseline", path.string() + " is not valid JSON");
    }
    spec.baseline_file = written;
  }

  std::vector<ReportMethodInput> methods;
  for (const MethodLayers& m : inputs.methods) {
    nlohmann::json params = nlohmann::json::object();
    for (const BakeEntry& e : job.bakes)
      if (e.stem == m.stem) params = e.resolved.is_object() ? e.resolved : e.params;
    methods.push_back({m.stem, m.method, m.seconds, params, &m.layers});
  }

  ReportOutcome outcome;
  try {
    outcome = build_report(spec, methods, inputs.reference);
  } catch (const std::invalid_argument& e) {
    throw InputError(job.file.string(), "/report", e.what());
  }
  stage.write_text("report.json", outcome.doc.dump(2) + "\n");
  ReportResult result;
  result.metrics_by_method = std::move(outcome.metrics_by_method);
  result.threshold_failures = std::move(outcome.failures);
  result.report = std::move(outcome.doc);
  return result;
}

}  // namespace hfbake
