// Glue between a baked job and report/report_document: reads the job's "report" options and the baseline
// file, builds report.json and stages it.
#include "cli/report_writer.hpp"

#include <map>
#include <optional>
#include <stdexcept>

#include "cli/method_dispatch.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/version.hpp"
#include "core/error.hpp"
#include "job/content_hash.hpp"
#include "job/schema_validation.hpp"
#include "methods/method_table.hpp"
#include "reference/bake_reference.hpp"
#include "reference/relief_reference.hpp"
#include "report/baseline_compare.hpp"
#include "report/report_document.hpp"

namespace hfbake {
namespace {

// The job's report.baseline, read and checked (read_report_file); nullopt when the job names none.
std::optional<nlohmann::json> read_baseline(const Job& job) {
  const nlohmann::json options = job.doc.value("report", nlohmann::json::object());
  if (!options.contains("baseline")) return std::nullopt;
  const auto path = job.resolve(options["baseline"].get<std::string>());
  try {
    return read_report_file(path);
  } catch (const InputError& e) {
    throw InputError(job.file.string(), "/report/baseline", e.line());
  }
}

}  // namespace

nlohmann::json read_report_file(const std::filesystem::path& file) {
  nlohmann::json doc = read_json_file(file);
  const std::vector<SchemaViolation> violations = validate_against_schema(doc, "report.schema.json");
  if (!violations.empty())
    throw InputError(file.string(), violations.front().pointer,
                     violations.front().message + " (not a report.json as hfbake writes it)");
  if (const auto impossible = impossible_report_value(doc))
    throw InputError(file.string(), impossible->first,
                     impossible->second + " (not a report.json as hfbake writes it)");
  return doc;
}

nlohmann::json job_scene(const Job& job) {
  nlohmann::json scene = nlohmann::json::object();
  for (const char* key : {"height", "surface", "environment", "lights", "bounces"})
    if (job.doc.contains(key)) scene[key] = job.doc[key];
  // Each input's bytes, with every file GDAL reads through it (a VRT's sources: cli/scene_inputs.hpp).
  std::map<std::string, ContentHash> inputs;
  for (const auto& [pointer, file] : job_read_files(job)) inputs[pointer].add_file(file);
  for (const auto& [pointer, h] : inputs) scene[nlohmann::json::json_pointer(pointer)] = "fnv1a:" + h.hex();
  return scene;
}

void check_report_baseline(const Job& job, int width, int height) {
  if (!job.has_reference) return;
  const std::optional<nlohmann::json> baseline = read_baseline(job);
  if (!baseline) return;
  // The parts of the report this job will write that identify it (build_report writes the same values).
  const nlohmann::json options = job.doc.value("report", nlohmann::json::object());
  const nlohmann::json now = {
      {"job", {{"name", job.name}, {"scene", job_scene(job)}}},
      {"size", {width, height}},
      {"crop", options.value("crop", 0)},
      {"reference", {{"parameters", job.doc.value("reference", nlohmann::json::object())}}}};
  const std::vector<std::string> differences = job_differences(now, *baseline);
  if (!differences.empty())
    throw InputError(job.file.string(), "/report/baseline",
                     job.resolve(options["baseline"].get<std::string>()).string() + " is " +
                         another_job_message(differences));
}

EntryReach entry_reach(const MethodConfig& config) {
  EntryReach r;
  const Falloff falloff = config.obscurance.value_or(Falloff{});
  r.falloff = falloff_kind_name(falloff.kind);
  r.radius = falloff.radius;
  r.cosine_weighted = config.cosine_weighted;
  if (config.holds<ReliefSettings>()) {
    const ReliefSettings& s = config.get<ReliefSettings>();
    r.search = relief_reference_record({s.directions, s.search_radius, s.compass, GridAxes{}});
  }
  return r;
}

ReportResult write_report(const Job& job, const std::string& job_hash, const ReportInputs& inputs,
                          OutputStage& stage) {
  const nlohmann::json options = job.doc.value("report", nlohmann::json::object());
  ReportSpec spec;
  spec.hfbake_version = hfbake_version();
  spec.job_name = job.name;
  spec.job_file = job.file.string();
  spec.job_hash = job_hash;
  spec.job_scene = job_scene(job);
  // Resolved: every default filled in (what the reference used).
  spec.reference_parameters = job.reference_options ? job.reference_options->resolved
                                                    : job.doc.value("reference", nlohmann::json::object());
  spec.reference_seconds = inputs.reference_seconds;
  spec.crop = options.value("crop", 0);
  spec.thresholds = options.value("thresholds", nlohmann::json::object());
  spec.baseline = read_baseline(job);
  if (spec.baseline) spec.baseline_file = options["baseline"].get<std::string>();

  std::vector<ReportMethodInput> methods;
  for (const MethodLayers& m : inputs.methods) {
    ReportMethodInput in{m.stem, m.method, m.seconds, nlohmann::json::object(), &m.layers, {}};
    for (const BakeEntry& e : job.bakes)
      if (e.stem == m.stem) {
        const MethodConfig& config = entry_config(e);
        in.parameters = config.resolved;
        in.reach = entry_reach(config);
      }
    methods.push_back(std::move(in));
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
