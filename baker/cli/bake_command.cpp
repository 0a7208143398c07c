#include "cli/bake_command.hpp"

#include <tbb/task_group.h>
#include <time.h>
#include <unistd.h>

#include <malloc.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "cli/bake_turns.hpp"
#include "cli/job_outcome.hpp"
#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/progress.hpp"
#include "cli/reference_cache.hpp"
#include "cli/report_page.hpp"
#include "cli/report_writer.hpp"
#include "cli/result_source.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/shard_command.hpp"
#include "cli/suite.hpp"
#include "cli/test_break.hpp"
#include "cli/texture_plan.hpp"
#include "cli/tile_command.hpp"
#include "cli/version.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "io/georaster_input.hpp"
#include "job/content_hash.hpp"
#include "job/manifest.hpp"
#include "reference/horizon_reference.hpp"
#include "reference/relief_reference.hpp"
#include "reference/sh_visibility_reference.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

std::size_t available_memory_bytes() {
  const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const long total = sysconf(_SC_PHYS_PAGES);
  // Use the larger of free and half the total: page cache counts as free enough for a bake.
  const double avail = std::max(double(pages), 0.5 * double(total)) * double(page);
  return std::size_t(avail);
}

// "7.1 GiB", or "35 MiB" below a GiB.
std::string gib(std::size_t bytes) {
  return memory_size_text(bytes);
}

// The budget as the caller gave it, named: "the 170 MiB of --memory-limit" (in bytes when gib() would round
// it: 10 bytes to "0 MiB"), or "the 7.1 GiB available (--memory-limit sets the budget)".
std::string budget_text(std::optional<std::size_t> limit, const std::string& limit_name) {
  const std::size_t have = limit ? *limit : available_memory_bytes();
  const std::size_t mib = std::size_t(1) << 20, half_gib = std::size_t(1) << 29;
  const bool exact = have % mib == 0 && (have < 2 * half_gib || have % half_gib == 0);
  return limit ? "the " + (exact ? gib(have) : std::to_string(have) + " bytes") + " of " + limit_name
               : "the " + gib(have) + " available (" + limit_name + " sets the budget)";
}

// "scene 35 MiB, p1 12 MiB": an estimate's parts for messages, and how they make the total when they are
// not simply added (MemoryPart).
std::string memory_parts_text(const std::vector<MemoryPart>& parts) {
  std::string t;
  int entries = 0;
  bool environment = false, libraries = false;
  for (const MemoryPart& p : parts) {
    t += (t.empty() ? "" : ", ") + p.name + " " + gib(p.bytes);
    entries += p.entry ? 1 : 0;
    environment = environment || p.name == "environment";
    libraries = libraries || p.name == kImageLibrariesPart;
  }
  if (entries > 1 || environment)
    t += entries > 1 ? "; the entries run one at a time, so the largest counts"
                     : "; the environment is read before the bake";
  if (entries > 1 && environment) t += ", the environment before them";
  if (libraries)
    t += "; the image libraries load once the first entry has run, to write its previews or textures";
  return t;
}

// The largest of an estimate's parts (null: none).
const MemoryPart* largest_part(const std::vector<MemoryPart>& parts) {
  const MemoryPart* largest = nullptr;
  for (const MemoryPart& p : parts)
    if (!largest || p.bytes > largest->bytes) largest = &p;
  return largest;
}

// "; the largest part, p2, shrinks with its directions (...)": what to change to make the job fit.
std::string largest_part_knob(const std::vector<MemoryPart>& parts) {
  const MemoryPart* largest = largest_part(parts);
  if (!largest || largest->knob.empty()) return "";
  return "; the largest part, " + largest->name + ", shrinks with " + largest->knob;
}

// What a job of the call plans for (plan_bake_turns): its estimate `need` and the process's part of it, or
// with --tiles the whole budget, which its tiles are sized to fill.
JobMemory planned_memory(const Job& job, FieldSize size, std::size_t need, bool tiles, std::size_t budget) {
  if (tiles) return {budget, 0};
  return {need, estimate_process_bytes(job, size)};
}

}  // namespace

std::size_t check_job_memory(const Job& job, FieldSize size, std::optional<std::size_t> limit,
                             std::string* parts_text, const std::string& limit_name) {
  const std::size_t have = limit ? *limit : available_memory_bytes();
  const std::string budget = budget_text(limit, limit_name);
  // The heights alone first: the estimate plans the sweeps, whose plan is itself about a byte per 128 texels
  // (a 1000000^2 field: 8 GB just to estimate), so a size far beyond the budget (its heights alone over four
  // times it) is refused before the plan is made; nearer ones get the estimate and its parts.
  const double heights = kProcessBytes + 4.0 * double(size.width) * double(size.height);
  if (heights > 4.0 * double(have))
    throw InputError(job.file.string(), "/height",
                     "a " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                         " field needs about " + gib(std::size_t(std::min(heights, 1.8e19))) +
                         " or more to bake (the process and the heights alone), more than " + budget);
  std::vector<MemoryPart> parts;
  const std::size_t need = estimate_peak_bytes(job, size, &parts);
  if (parts_text) *parts_text = memory_parts_text(parts);
  // Named at the key whose input is the largest part when that is the environment's image (its size, not
  // the field's, is what to change), else at the field.
  const MemoryPart* largest = largest_part(parts);
  const std::string where = largest && largest->name == "environment" ? "/environment" : "/height";
  if (need > have)
    throw InputError(job.file.string(), where,
                     "a " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                         " field needs about " + gib(need) + " to bake (" + memory_parts_text(parts) +
                         "), more than " + budget + largest_part_knob(parts));
  return need;
}

namespace {

// `params`: the resolved parameters (every default filled in), what the bake used.
void add_common_attributes(LayerSet& layers, const Job& job, const std::string& job_hash,
                           const std::string& method, const nlohmann::json& params, double seconds) {
  layers.attributes.emplace_back("hfbake:version", hfbake_version());
  layers.attributes.emplace_back("hfbake:job", job.name);
  layers.attributes.emplace_back("hfbake:job_hash", job_hash);
  layers.attributes.emplace_back("hfbake:method", method);
  layers.attributes.emplace_back("hfbake:parameters", params.dump());
  layers.attributes.emplace_back("hfbake:wall_seconds", std::to_string(seconds));
}

// The height field's own layers for textures (kHeightStem): "normal", the unit surface normal of each texel
// (the scene's when it holds them).
LayerSet height_layers(const Scene& scene) {
  LayerSet set;
  set.width = scene.field.width;
  set.height = scene.field.height;
  const std::vector<Vec3f> computed =
      scene.normals.empty() ? compute_normals(scene.field) : std::vector<Vec3f>();
  const std::vector<Vec3f>& normals = scene.normals.empty() ? computed : scene.normals;
  std::vector<float> data(normals.size() * 3);
  for (std::size_t t = 0; t < normals.size(); ++t) {
    data[3 * t] = normals[t].x;
    data[3 * t + 1] = normals[t].y;
    data[3 * t + 2] = normals[t].z;
  }
  set.adopt("normal", xyz_channels(), std::move(data));
  return set;
}

// One job's way through bake_job: where its progress and notices go, its staging folder, its outcome.
struct JobRun {
  const Job& job;
  Progress& progress;
  const std::atomic<bool>& cancel;
  JobOutcome& outcome;
  OutputStage& stage;
  std::string job_hash;

  void tell(const std::vector<std::string>& notices) const {
    const std::string warning = "warning: ";
    for (const std::string& n : notices)
      if (n.rfind(warning, 0) == 0) {
        progress.warning(job.name + ": " + n);
        outcome.warnings.push_back(n.substr(warning.size()));
      } else
        progress.message(job.name + ": " + n);
  }
  // A RunControl reporting `step`'s progress and stopping when the bake is cancelled.
  RunControl control(const std::string& step) const {
    if (cancel.load()) throw Cancelled();
    RunControl rc;
    rc.cancel = &cancel;
    rc.progress = [this, step](double f) { progress.update(job.name, step, f); };
    return rc;
  }
};

// Load: the scene, the heights line, and the height field's own textures.
Scene load_step(const JobRun& run) {
  run.progress.begin(run.job.name, "load");
  const auto t0 = std::chrono::steady_clock::now();
  Scene scene = load_scene(run.job, [&](double f) { run.progress.update(run.job.name, "load", f); });
  const HeightsReport heights = describe_heights(run.job, scene);
  run.progress.message(run.job.name + ": " + heights.line);
  if (!heights.warning.empty()) {
    run.progress.warning("warning: " + run.job.name + ": " + heights.warning);
    run.outcome.warnings.push_back(run.job.file.string() + ": " + heights.warning);
  }
  run.stage.set_georeference(scene.georeference);
  run.stage.set_texel_size(scene.field.dx(), scene.field.dy());
  run.progress.end(run.job.name, "load", seconds_since(t0));
  const std::vector<PlannedTexture> textures = plan_textures(run.job);
  if (std::any_of(textures.begin(), textures.end(),
                  [](const PlannedTexture& t) { return t.stem == kHeightStem; }))
    run.tell(run.stage.write_textures(kHeightStem, height_layers(scene)));
  return scene;
}

// Bake: each entry's layers from the source, staged; kept for the report when the job has a reference.
void bake_step(const JobRun& run, ResultSource& source, ReportInputs& report,
               std::map<std::string, LayerSet>* kept) {
  const Job& job = run.job;
  for (std::size_t index = 0; index < job.bakes.size(); ++index) {
    const BakeEntry& entry = job.bakes[index];
    const RunControl rc = run.control(entry.stem);
    run.progress.begin(job.name, entry.stem);
    SourcedLayers result = source.method(int(index), rc);
    LayerSet& layers = result.layers;
    if (apply_test_break(entry.method, entry.stem, layers))
      run.progress.message(job.name + ": " + entry.stem +
                           ": HFBAKE_TEST_BREAK is set: its values are broken on purpose");
    run.progress.end(job.name, entry.stem, result.seconds);
    add_common_attributes(layers, job, run.job_hash, entry.method, entry_config(entry).resolved,
                          result.seconds);
    run.tell(run.stage.write_layers(entry.stem, layers));
    if (kept) (*kept)[entry.stem] = job.has_reference ? layers : std::move(layers);
    run.outcome.methods[entry.stem] = {
        {"method", entry.method}, {"seconds", result.seconds}, {"cpu_seconds", result.cpu_seconds}};
    if (job.has_reference)
      report.methods.push_back({entry.stem, entry.method, result.seconds, std::move(layers)});
  }
}

// Reference: the cache's entry when it holds this job's reference, else the source's (then stored in the
// cache; a damaged entry is recomputed and replaced); then the layers traced after the paths (horizons, SH
// visibility, relief's), staged.
SourcedLayers reference_step(const JobRun& run, ResultSource& source, const ReferenceCache* cache,
                             FieldSize size, const Scene& scene, const ReportInputs& report,
                             std::string* cache_note) {
  const Job& job = run.job;
  const RunControl rc = run.control("reference");
  run.progress.begin(job.name, "reference");
  const auto t0 = std::chrono::steady_clock::now();
  std::string cache_key;
  ReferenceCache::Entry cached;
  CacheLookup lookup = CacheLookup::miss;
  if (cache) {
    cache_key = reference_cache_key(job);
    lookup = cache->load(cache_key, cached, size.width, size.height);
    if (lookup == CacheLookup::corrupt)
      run.progress.warning("warning: " + job.name + ": reference cache entry " +
                           cache->entry_path(cache_key).string() +
                           " was damaged: removed, computing the reference again");
  }
  SourcedLayers result;
  if (lookup == CacheLookup::hit) {
    result.layers = std::move(cached.layers);
    result.seconds = seconds_since(t0);
    *cache_note =
        "read from the reference cache (computing it took " + std::to_string(cached.seconds) + " s)";
  } else {
    result = source.reference(rc);
    run.tell(result.notices);
  }
  if (cache && lookup != CacheLookup::hit) {
    const std::string problem = cache->store(cache_key, result.layers, result.seconds);
    // A warning, shown with --quiet too: the next bake will trace the reference again.
    if (!problem.empty())
      run.progress.warning("warning: " + job.name +
                           ": the reference cache cannot keep this reference: " + problem);
  }
  run.progress.end(job.name, "reference", result.seconds);
  LayerSet& reference = result.layers;
  std::vector<const LayerSet*> method_layers;
  for (const MethodLayers& m : report.methods) method_layers.push_back(&m.layers);
  // Not cached; a step of their own, since a horizon layer's bisections can outlast a few samples' paths
  // (512^2, K = 32: minutes).
  const bool traces_more = std::any_of(method_layers.begin(), method_layers.end(), [](const LayerSet* m) {
    return m->find("horizon") || m->find("horizon_distance") || m->find("sh_visibility");
  });
  const auto t1 = std::chrono::steady_clock::now();
  if (traces_more) run.progress.begin(job.name, "reference horizons");
  add_reference_horizons(scene.field, method_layers, reference, run.control("reference horizons"),
                         scene.curvature);
  add_reference_sh_visibility(scene.field, method_layers, reference, rc);
  if (traces_more) run.progress.end(job.name, "reference horizons", seconds_since(t1));
  // The first relief entry's layers, traced with its settings.
  for (std::size_t i = 0; i < job.bakes.size(); ++i)
    if (const MethodConfig& c = entry_config(job.bakes[i]); c.holds<ReliefSettings>()) {
      add_reference_relief(scene.field, c.get<ReliefSettings>(), report.methods[i].layers, reference, rc,
                           scene.curvature, grid_axes(scene.georeference));
      break;
    }
  add_common_attributes(reference, job, run.job_hash, "reference", job_reference_options(job).resolved,
                        result.seconds);
  run.tell(run.stage.write_layers("reference", reference));
  nlohmann::json& record = run.outcome.methods["reference"];
  record = result.record;
  record["method"] = "reference";
  record["seconds"] = result.seconds;
  if (cache) {
    record["cache"] = lookup == CacheLookup::corrupt ? "rebuilt" : cache_lookup_name(lookup);
    record["cache_key"] = cache_key;
    if (lookup == CacheLookup::hit) record["cache_saved_seconds"] = cached.seconds;
  }
  return result;
}

// Report: report.json and report.html staged, the thresholds and the baseline into the outcome.
void report_step(const JobRun& run, const ReportInputs& report, const std::string& cache_note) {
  const ReportResult r = write_report(run.job, run.job_hash, report, run.stage);
  write_report_page(run.job, report, r.report, run.stage, cache_note);
  for (auto& [stem, metrics] : r.metrics_by_method.items())
    if (run.outcome.methods.contains(stem)) run.outcome.methods[stem]["metrics"] = metrics;
  if (r.report.contains("baseline")) run.outcome.baseline = r.report["baseline"];
  for (const std::string& failure : r.threshold_failures) {
    run.outcome.errors.push_back(run.job.file.string() + ": /report/thresholds: " + failure);
    run.outcome.status = JobStatus::threshold_failed;
  }
}

}  // namespace

void bake_job(const Job& job, Progress& progress, const std::atomic<bool>& cancel, JobOutcome& outcome,
              const ReferenceCache* cache, const BakeOptions& options,
              std::map<std::string, LayerSet>* kept) {
  const FieldSize size = probe_field_size(job);
  if (options.tiles) {  // the tiles' plan holds them to the budget, whatever the raster's size
    bake_tiled(job, progress, cancel, outcome, options,
               options.memory_limit ? *options.memory_limit : available_memory_bytes());
    return;
  }
  check_job_memory(job, size, options.memory_limit, nullptr, options.memory_limit_name);
  check_report_baseline(job, size.width, size.height);  // a baseline of another job: refused before baking
  if (options.shard) {
    // Another job file's outputs of this name in the folder: refused as the merge would refuse them.
    check_output_owner(job, options.overwrite);
    claim_shards_folder(job, options.overwrite);  // the job's name in shards/: this job file's
    const fs::path made = bake_shard(job, *options.shard, progress, cancel, outcome, cache, options.stage);
    if (!made.empty()) outcome.outputs = {made};
    return;
  }
  // hfbake merge takes the results from the shards, every one checked before anything is written.
  std::optional<MergedShards> shards;
  if (options.merge) {
    check_shards_owner(job, options.overwrite);  // shards of this name another job file baked
    shards.emplace(job, size.width, size.height);
  }
  OutputStage stage(job, options.overwrite);
  for (const std::string& line : stage.notes()) progress.message(job.name + ": " + line);
  JobRun run{job, progress, cancel, outcome, stage, ""};

  const Scene scene = load_step(run);
  run.job_hash = job_content_hash(job);
  ResultSource source = shards ? merged_results(*shards, scene) : computed_results(job, scene, stage, size);
  ReportInputs report;
  bake_step(run, source, report, kept);
  if (job.has_reference) {
    std::string cache_note;
    SourcedLayers reference = reference_step(run, source, cache, size, scene, report, &cache_note);
    report.reference = std::move(reference.layers);
    report.reference_seconds = reference.seconds;
    if (kept) (*kept)["reference"] = report.reference;
    report_step(run, report, cache_note);
  }
  if (cancel.load()) throw Cancelled();
  outcome.outputs = stage.commit();
  for (const fs::path& p : outcome.outputs) progress.message(job.name + ": wrote " + p.string());
  for (const fs::path& p : stage.removed())
    progress.message(job.name + ": removed " + p.string() +
                     " (its previous bake's, not written by this one)");
}

namespace {

void print_summary(const std::vector<JobOutcome>& outcomes, bool quiet) {
  if (quiet) return;
  std::fprintf(stderr, "\nhfbake summary\n");
  for (const JobOutcome& o : outcomes) {
    // Names and paths as printable text: a control character in a folder's name would start a line or a
    // terminal escape.
    const std::string file = printable(o.file), name = o.name.empty() ? file : printable(o.name);
    std::fprintf(stderr, "  %-24s %-16s %8.2f s  %s\n", name.c_str(), job_status_name(o.status), o.seconds,
                 file.c_str());
    for (auto& [stem, m] : o.methods.items()) {
      std::fprintf(stderr, "      %-20s %8.2f s", stem.c_str(), m.value("seconds", 0.0));
      if (m.contains("cache")) {
        const std::string c = m["cache"].get<std::string>();
        if (c == "hit")
          std::fprintf(stderr, "  (reference cache hit: saved %.2f s)", m.value("cache_saved_seconds", 0.0));
        else
          std::fprintf(stderr, "  (reference cache %s)", c.c_str());
      }
      // The error beyond the reference's noise (rmse includes that noise).
      if (m.contains("metrics"))
        for (auto& [layer, metrics] : m["metrics"].items())
          if (metrics.contains("excess_rmse"))
            std::fprintf(stderr, "  %s excess %.2g (rmse %.2g, reference noise %.2g)", layer.c_str(),
                         metrics["excess_rmse"].get<double>(), metrics.value("rmse", 0.0),
                         metrics.value("noise_rmse", 0.0));
      std::fprintf(stderr, "\n");
    }
    if (!o.outputs.empty()) {
      // The folder holding them all (the output folder, above its textures/).
      fs::path common = o.outputs.front().parent_path();
      for (const fs::path& out : o.outputs)
        while (!common.empty() &&
               std::mismatch(common.begin(), common.end(), out.begin(), out.end()).first != common.end())
          common = common.parent_path();
      std::fprintf(stderr, "      outputs in %s\n", printable(common.string()).c_str());
    }
  }
  int hits = 0, computed = 0;
  double saved = 0;
  for (const JobOutcome& o : outcomes)
    if (o.methods.contains("reference") && o.methods["reference"].contains("cache")) {
      const bool hit = o.methods["reference"]["cache"] == "hit";
      hits += hit, computed += !hit;
      saved += o.methods["reference"].value("cache_saved_seconds", 0.0);
    }
  if (hits + computed > 0)
    std::fprintf(stderr, "  reference cache: %d hit%s (%.2f s of path tracing saved), %d computed\n", hits,
                 hits == 1 ? "" : "s", saved, computed);
}

void write_summary_file(const fs::path& file, const std::vector<JobOutcome>& outcomes, int exit_code) {
  nlohmann::json doc = {{"hfbake_version", hfbake_version()}, {"exit_code", exit_code}};
  doc["jobs"] = nlohmann::json::array();
  for (const JobOutcome& o : outcomes) {
    nlohmann::json j = {{"file", fs::absolute(o.file).string()},
                        {"name", o.name},
                        {"status", job_status_name(o.status)},
                        {"seconds", o.seconds},
                        {"errors", o.errors},
                        {"methods", o.methods}};
    j["outputs"] = nlohmann::json::array();
    for (const fs::path& p : o.outputs) j["outputs"].push_back(fs::absolute(p).string());
    doc["jobs"].push_back(std::move(j));
  }
  // Atomic like every other output: a temporary of its own beside the file, then rename (a full disk or a
  // read-only folder leaves no temporary behind).
  try {
    write_named_output(file, doc.dump(2) + "\n");
  } catch (const std::system_error& e) {
    throw InputError(file.string(), "--summary", "cannot write file: " + e.code().message());
  }
}

// For job i of one call, a line for each other job whose outputs would be the same files
// (docs/output_folders.md): the same output folder, however written, and the same name (every output), or
// both with a reference (report.json and report.html, which carry no job name). Null entries are skipped.
std::vector<std::string> output_collisions(const std::vector<const Job*>& jobs, std::size_t i) {
  std::vector<std::string> lines;
  if (!jobs[i]) return lines;
  const Job& a = *jobs[i];
  const auto folder = [](const fs::path& d) {  // "out", "./out/" and a link to it: one folder
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::absolute(d), ec);
    if (ec) p = fs::absolute(d).lexically_normal();
    return p.has_filename() ? p : p.parent_path();
  };
  const fs::path dir = folder(a.output.dir);
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    if (k == i || !jobs[k]) continue;
    const Job& b = *jobs[k];
    std::error_code ec;
    if (fs::equivalent(a.file, b.file, ec)) {  // one line, at the second naming
      if (k < i && std::none_of(jobs.begin(), jobs.begin() + std::ptrdiff_t(k),
                                [&](const Job* j) { return j && fs::equivalent(j->file, a.file, ec); }))
        lines.push_back(a.file.string() + ": is named more than once: give each job file once");
      continue;
    }
    if (folder(b.output.dir) != dir) continue;
    if (a.name == b.name)
      lines.push_back(a.file.string() + ": /name: its outputs (" + a.output_path("*", ".exr").string() +
                      (a.has_reference && b.has_reference ? ", report.json" : "") +
                      ") would be the same files as " + b.file.string() +
                      "'s (give one another name or output folder)");
    else if (a.has_reference && b.has_reference)
      lines.push_back(a.file.string() + ": /output/dir: its report (" +
                      (a.output.dir / "report.json").string() + ", report.html) would be the same files as " +
                      b.file.string() + "'s (both have a reference: give each its own output folder)");
  }
  return lines;
}

}  // namespace

std::optional<std::size_t> parse_memory_size(const std::string& text) {
  // Decimal digits first (std::stod alone also takes "0x100", "inf" and leading blanks).
  if (text.empty() || !(std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '.') ||
      text.find_first_of("xX") != std::string::npos)
    return std::nullopt;
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::string unit = text.substr(used);
  for (const char* tail : {"iB", "B"})
    if (unit.size() >= std::char_traits<char>::length(tail) &&
        unit.compare(unit.size() - std::char_traits<char>::length(tail), std::string::npos, tail) == 0) {
      unit.resize(unit.size() - std::char_traits<char>::length(tail));
      break;
    }
  double scale = 1;
  if (unit == "K" || unit == "k")
    scale = 1024.0;
  else if (unit == "M" || unit == "m")
    scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "g")
    scale = 1024.0 * 1024 * 1024;
  else if (unit == "T" || unit == "t")
    scale = 1024.0 * 1024 * 1024 * 1024;
  else if (!unit.empty())
    return std::nullopt;
  const double bytes = value * scale;
  if (!(bytes >= 1) || !(bytes < 1.8e19)) return std::nullopt;
  return std::size_t(bytes);
}

int run_validate(const std::vector<fs::path>& files, bool quiet, std::optional<std::size_t> memory_limit,
                 bool tiles, std::optional<int> tile_size, bool overwrite) {
  int exit_code = 0;
  // A suite validates as the jobs it lists, each in the output folder `bake` gives it.
  const CallJobs call = call_jobs(files, std::nullopt);
  for (const Suite& suite : call.suites) {
    for (const std::string& s : suite.skipped) std::fprintf(stderr, "hfbake: note: %s\n", s.c_str());
    if (!quiet)
      std::fprintf(stderr, "hfbake: %s: suite of %zu jobs\n", suite.file.c_str(), suite.jobs.size());
  }
  for (const std::string& e : call.errors) std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
  if (!call.errors.empty()) exit_code = 2;
  // Every job loaded and resolved first: jobs whose outputs collide are refused as bake refuses them.
  std::vector<JobLoad> loads;
  for (const CallJob& job : call.jobs) {
    JobLoad load = load_job(job.file, job.out, job.out_key);
    if (load.job) load.errors = resolve_job(*load.job);
    if (!load.errors.empty()) load.job.reset();
    loads.push_back(std::move(load));
  }
  {
    std::vector<const Job*> valid;
    for (const JobLoad& l : loads) valid.push_back(l.job ? &*l.job : nullptr);
    for (std::size_t i = 0; i < loads.size(); ++i) {
      std::vector<std::string> lines = output_collisions(valid, i);
      loads[i].errors.insert(loads[i].errors.end(), lines.begin(), lines.end());
      if (loads[i].job) try {
          check_output_owner(*loads[i].job, overwrite);  // another job file's outputs of this name there
          if (tiles) check_tiles_folder(*loads[i].job, overwrite);  // as its tile tasks and merge find tiles/
        } catch (const InputError& e) {
          loads[i].errors.push_back(e.line());
        }
    }
  }
  const std::size_t budget = memory_limit ? *memory_limit : available_memory_bytes();
  std::vector<JobMemory> planned;  // the valid jobs', for the plan of their turns
  for (std::size_t n = 0; n < call.jobs.size(); ++n) {
    const fs::path& file = call.jobs[n].file;
    JobLoad& load = loads[n];
    for (const std::string& e : load.errors) std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
    if (!load.job || !load.errors.empty()) {
      exit_code = 2;
      continue;
    }
    try {
      const FieldSize size = probe_field_size(*load.job);
      if (tiles) {
        const std::string plan = validate_tiled(*load.job, budget, tile_size);
        if (!quiet)
          std::fprintf(stderr, "hfbake: %s: valid (%dx%d in %s)\n", printable(file.string()).c_str(),
                       size.width, size.height, plan.c_str());
        planned.push_back(planned_memory(*load.job, size, 0, true, budget));
        continue;
      }
      std::string parts;
      const std::size_t need = check_job_memory(*load.job, size, memory_limit, &parts);
      check_report_baseline(*load.job, size.width, size.height);
      // Everything bake refuses about the inputs, refused here first: the same loader reads every image
      // (NaN heights without nodata, environment aspect ratios, channel names, map sizes).
      const Scene scene = load_scene(*load.job);
      const HeightsReport heights = describe_heights(*load.job, scene);
      if (!heights.warning.empty())
        std::fprintf(stderr, "hfbake: warning: %s\n",
                     printable(file.string() + ": " + heights.warning).c_str());
      if (!quiet) {
        const std::string shown = printable(file.string());
        std::fprintf(stderr, "hfbake: %s: %s\nhfbake: %s: valid (%dx%d, about %s to bake: %s)\n",
                     shown.c_str(), printable(heights.line).c_str(), shown.c_str(), size.width, size.height,
                     gib(need).c_str(), parts.c_str());
      }
      planned.push_back(planned_memory(*load.job, size, need, false, budget));
    } catch (const InputError& e) {
      std::fprintf(stderr, "hfbake: error: %s\n", e.line().c_str());
      exit_code = 2;
    } catch (const std::exception& e) {  // std::bad_alloc reading an input: one line, as bake says it
      std::fprintf(stderr, "hfbake: error: %s\n", printable(file.string() + ": " + e.what()).c_str());
      exit_code = 2;
    }
  }
  // Several jobs: the turns a bake of them takes and the peak it plans for (refused as bake refuses it when
  // even one at a time they do not fit).
  if (planned.size() > 1) {
    const BakeTurns turns = plan_bake_turns(planned, budget);
    const std::string text = bake_turns_text(turns, budget_text(memory_limit, "--memory-limit"));
    if (!turns.fits) {
      std::string files;
      for (const JobLoad& l : loads)
        if (l.job) files += (files.empty() ? "" : ", ") + l.job->file.string();
      std::fprintf(stderr, "hfbake: error: %s\n", printable(files + ": " + text).c_str());
      exit_code = 2;
    } else if (!quiet) {
      std::fprintf(stderr, "hfbake: %s\n", text.c_str());
    }
  }
  return exit_code;
}

bool bake_interrupted(const std::vector<JobOutcome>& outcomes, bool cancel) {
  return cancel && std::any_of(outcomes.begin(), outcomes.end(),
                               [](const JobOutcome& o) { return o.status == JobStatus::cancelled; });
}

int bake_exit_status(const std::vector<JobOutcome>& outcomes, bool interrupted, int signal) {
  if (interrupted) return 128 + (signal > 0 ? signal : SIGINT);
  int code = 0;
  for (const JobOutcome& o : outcomes) {
    if (o.status == JobStatus::threshold_failed) code = std::max(code, 1);
    if (o.status == JobStatus::invalid || o.status == JobStatus::failed) code = std::max(code, 2);
  }
  return code;
}

int run_bake(const BakeOptions& options, const std::atomic<bool>& cancel) {
  const auto t_start = std::chrono::steady_clock::now();
  const Progress::Mode mode = Progress::detect(options.quiet);
  Progress progress(mode);

  // The call's jobs, suites expanded, each with the output folder the call gives it.
  const CallJobs call = call_jobs(options.jobs, options.out);
  for (const Suite& suite : call.suites)
    for (const std::string& s : suite.skipped) std::fprintf(stderr, "hfbake: note: %s\n", s.c_str());
  int exit_code = 0;
  for (const std::string& e : call.errors) {
    std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
    exit_code = 2;
  }
  const std::vector<CallJob>& inputs = call.jobs;
  const std::vector<Suite>& suites = call.suites;

  std::vector<JobOutcome> outcomes(inputs.size());
  std::vector<std::optional<Job>> jobs(inputs.size());
  // Validate everything first: a typo in the last job is reported before hours of baking.
  std::vector<fs::path> read = options.jobs;  // every file the bake reads: a summary may not replace one
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    JobLoad load = load_job(inputs[i].file, inputs[i].out, inputs[i].out_key);
    read.push_back(inputs[i].file);
    try {  // an invalid job's inputs too, as far as its document says them
      const nlohmann::json doc = load.job ? load.job->doc : read_json_file(inputs[i].file);
      const fs::path base = fs::absolute(inputs[i].file).parent_path();
      for (const auto& [ptr, rel] : job_input_files(doc))
        for (const fs::path& f : raster_files(base / rel)) read.push_back(f);  // and a VRT's sources
    } catch (const std::exception&) {
    }
    if (load.job) {
      load.errors = resolve_job(*load.job);
      if (!load.errors.empty()) load.job.reset();
    }
    outcomes[i].file = inputs[i].file.string();
    for (const std::string& e : load.errors) {
      std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
      outcomes[i].errors.push_back(e);
    }
    if (load.job) {
      outcomes[i].name = load.job->name;
      jobs[i] = std::move(load.job);
    } else {
      outcomes[i].status = JobStatus::invalid;
    }
  }
  // Two jobs whose outputs would land on the same paths: both refused before anything is baked, naming
  // each other (one would silently replace the other's files).
  {
    std::vector<const Job*> valid;
    for (const std::optional<Job>& j : jobs) valid.push_back(j ? &*j : nullptr);
    for (std::size_t i = 0; i < jobs.size(); ++i)
      for (const std::string& e : output_collisions(valid, i)) {
        std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
        outcomes[i].errors.push_back(e);
        outcomes[i].status = JobStatus::invalid;
      }
  }
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (outcomes[i].status == JobStatus::invalid) jobs[i].reset();
  // What each job plans for, a job that cannot fit the budget alone refused here; the others then bake in
  // turns, together only while their combined estimate fits the budget (plan_bake_turns).
  const std::size_t budget = options.memory_limit ? *options.memory_limit : available_memory_bytes();
  std::vector<JobMemory> planned;
  std::vector<std::size_t> planned_jobs;  // the index of each planned job
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (!jobs[i]) continue;
    try {
      const FieldSize size = probe_field_size(*jobs[i]);
      const std::size_t need = options.tiles ? 0
                                             : check_job_memory(*jobs[i], size, options.memory_limit, nullptr,
                                                                options.memory_limit_name);
      planned.push_back(planned_memory(*jobs[i], size, need, options.tiles, budget));
      planned_jobs.push_back(i);
    } catch (const InputError& e) {
      std::fprintf(stderr, "hfbake: error: %s\n", e.line().c_str());
      outcomes[i].errors.push_back(e.line());
      outcomes[i].status = JobStatus::invalid;
      jobs[i].reset();
    }
  }
  // Jobs that do not fit the budget even one at a time beside the libraries the call loads: the call is
  // refused before anything is baked.
  if (planned.size() > 1) {
    const BakeTurns turns = plan_bake_turns(planned, budget);
    if (!turns.fits) {
      std::string files;
      for (std::size_t k : planned_jobs) files += (files.empty() ? "" : ", ") + jobs[k]->file.string();
      const std::string line =
          printable(files + ": " +
                    bake_turns_text(turns, budget_text(options.memory_limit, options.memory_limit_name)));
      std::fprintf(stderr, "hfbake: error: %s\n", line.c_str());
      for (std::size_t k : planned_jobs) {
        outcomes[k].errors.push_back(line);
        outcomes[k].status = JobStatus::invalid;
        jobs[k].reset();
      }
      planned.clear(), planned_jobs.clear();
    }
  }
  // A summary written over a job, a suite or an input, or where a job writes (an output, its owner record,
  // its lock) or a suite its reports: refused before anything is baked (and no summary).
  if (options.summary) {
    if (const std::string why = named_output_problem(*options.summary); !why.empty()) {
      std::fprintf(stderr, "hfbake: error: %s\n",
                   printable(options.summary->string() + ": --summary: " + why).c_str());
      return 2;
    }
    for (const fs::path& f : read) {
      std::error_code ec;
      if (fs::equivalent(*options.summary, f, ec) && !ec) {
        std::fprintf(stderr, "hfbake: error: %s\n",
                     printable(options.summary->string() + ": --summary: is " + f.string() +
                               ", which this bake reads: give the summary another name")
                         .c_str());
        return 2;
      }
    }
    std::error_code ec;
    const fs::path summary = fs::weakly_canonical(fs::absolute(*options.summary), ec);
    for (const Suite& suite : suites) {
      std::vector<fs::path> names = suite_report_files(suite);
      names.push_back(suite_lock_file(suite));
      for (const fs::path& report : names)
        if (fs::weakly_canonical(report, ec) == summary) {
          std::fprintf(stderr, "hfbake: error: %s\n",
                       printable(options.summary->string() + ": --summary: is where suite " + suite.name +
                                 " writes " + report.filename().string() + ": give the summary another name")
                           .c_str());
          return 2;
        }
    }
    for (const std::optional<Job>& job : jobs)
      if (job && writes_in_output_folder(*job, *options.summary)) {
        std::fprintf(stderr, "hfbake: error: %s\n",
                     printable(options.summary->string() + ": --summary: is where job " + job->name +
                               " writes its outputs in " + job->output.dir.string() +
                               ": give the summary another name")
                         .c_str());
        return 2;
      }
  }

  std::optional<ReferenceCache> cache;
  if (!options.no_cache) {
    if (options.cache)
      cache.emplace(fs::absolute(*options.cache));
    else if (const auto dir = default_reference_cache_dir())
      cache.emplace(*dir);
  }

  std::mutex error_mutex;
  auto fail = [&](JobOutcome& o, JobStatus s, const std::string& line) {
    std::lock_guard lock(error_mutex);
    o.status = s;
    o.errors.push_back(line);
    progress.error(line);
  };
  // The jobs of one turn (plan_bake_turns) run concurrently and share the cores with their own parallel
  // loops; the turns run one after another. The last job of a turn runs on this thread (run_and_wait, which
  // ends the turn), so a single job's allocations always come from the same malloc arena: its peak resident
  // memory does not depend on which thread the scheduler hands it (docs/large-fields.md).
  tbb::task_group group;
  std::vector<bool> ends_turn(jobs.size(), false);
  for (const std::vector<std::size_t>& turn : plan_bake_turns(planned, budget).turns)
    ends_turn[planned_jobs[turn.back()]] = true;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (!jobs[i]) continue;
    auto run_job = [&, i] {
      JobOutcome& o = outcomes[i];
      const auto t_job = std::chrono::steady_clock::now();
      // However the job ends, the summary shows how long it ran (not 0 s for an interrupted job).
      struct Timer {
        JobOutcome& o;
        std::chrono::steady_clock::time_point t0;
        ~Timer() { o.seconds = seconds_since(t0); }
      } timer{o, t_job};
      try {
        bake_job(*jobs[i], progress, cancel, o, cache ? &*cache : nullptr, options);
      } catch (const Cancelled&) {
        o.status = JobStatus::cancelled;
      } catch (const OutputError& e) {  // a full disk: the job is not at fault
        fail(o, JobStatus::failed, e.line());
      } catch (const InputError& e) {
        fail(o, JobStatus::invalid, e.line());
      } catch (const std::exception& e) {
        fail(o, JobStatus::failed, jobs[i]->file.string() + ": " + e.what());
      }
    };
    if (ends_turn[i]) {
      group.run_and_wait(run_job);
      // What the turn freed goes back to the system before the next turn allocates: malloc keeps freed
      // memory in its arenas otherwise, and the next turn's jobs may allocate from other threads' arenas.
      malloc_trim(0);
    } else
      group.run(run_job);
  }
  group.wait();

  const bool interrupted = bake_interrupted(outcomes, cancel.load());
  if (cancel.load() && !interrupted)
    std::fprintf(stderr,
                 "hfbake: note: the stop signal came after every job had ended; nothing was "
                 "interrupted\n");
  exit_code =
      std::max(exit_code, bake_exit_status(outcomes, interrupted,
                                           options.interrupt_signal ? options.interrupt_signal->load() : 0));
  print_summary(outcomes, options.quiet);
  const double total_seconds = seconds_since(t_start);
  for (std::size_t s = 0; s < suites.size() && !interrupted && !options.shard; ++s) {
    std::vector<JobOutcome> members;
    for (std::size_t i = 0; i < inputs.size(); ++i)
      if (inputs[i].suite == int(s)) members.push_back(outcomes[i]);
    try {
      const SuiteReports written = write_suite_reports(suites[s], members, total_seconds);
      for (const std::string& w : written.warnings) std::fprintf(stderr, "hfbake: warning: %s\n", w.c_str());
      for (const fs::path& p : written.files)
        progress.message("suite " + suites[s].name + ": wrote " + p.string());
    } catch (const InputError& e) {
      progress.error(suites[s].file.string() + ": cannot write the suite reports: " + e.line());
      exit_code = std::max(exit_code, 2);
    } catch (const std::exception& e) {
      progress.error(suites[s].file.string() + ": cannot write the suite reports: " + e.what());
      exit_code = std::max(exit_code, 2);
    }
  }
  for (const JobOutcome& o : outcomes)
    for (const std::string& e : o.errors)
      if (o.status == JobStatus::threshold_failed) std::fprintf(stderr, "hfbake: error: %s\n", e.c_str());
  if (options.summary) {
    try {
      write_summary_file(*options.summary, outcomes, exit_code);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "hfbake: error: %s: cannot write summary: %s\n", options.summary->c_str(),
                   e.what());
      exit_code = std::max(exit_code, 2);
    }
  }
  return exit_code;
}

}  // namespace hfbake
