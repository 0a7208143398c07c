#include "cli/method_dispatch.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "cli/outputs.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/texture_plan.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "farm/shard_plan.hpp"
#include "io/color.hpp"
#include "report/compare.hpp"

namespace hfbake {
namespace fs = std::filesystem;

MethodContext job_method_context(const Job& job) {
  MethodContext c;
  const FieldSize size = probe_field_size(job);
  const nlohmann::json& h = job.doc["height"];
  c.field.width = size.width;
  c.field.height = size.height;
  const std::array<double, 2> sides = job_texel_sides(job);
  c.field.texel_size = sides[0];
  if (sides[1] != sides[0]) c.field.texel_size_y = sides[1];
  c.curvature = job_curvature(job, h.contains("image") && image_geographic(job)).on;
  c.field.wrap = h.value("wrap", "clamp") == "repeat" ? Wrap::repeat : Wrap::clamp;
  c.bounces = job_bounces(job);
  c.uniform_environment = job_environment_uniform(job.doc);
  if (h.contains("image"))
    if (const std::optional<GeoHeightBand> band = georaster_height_band(job))
      c.placed = band->georeference.has_site;
  return c;
}

namespace {

// What the report makes of report.crop and report.thresholds, checked before anything is baked: a crop
// that leaves a texel of the field, thresholds "<stem>.<layer>.<metric>" of a bake entry of the job and a
// metric the report computes (the layer is known only once the reference has been compared).
void check_report_settings(const Job& job, const MethodContext& context) {
  if (!job.doc.contains("report")) return;
  const nlohmann::json& report = job.doc["report"];
  const std::string file = job.file.string();
  if (report.contains("crop")) {
    const int crop = report["crop"].get<int>();
    const CompareRegion r = crop_region(context.field.width, context.field.height, crop);
    if (r.x1 <= r.x0 || r.y1 <= r.y0)
      throw InputError(file, "/report/crop",
                       std::to_string(crop) + " leaves no texel of the " +
                           std::to_string(context.field.width) + "x" + std::to_string(context.field.height) +
                           " field");
  }
  // Thresholds and a baseline score the methods against the reference: without one nothing is scored, and a
  // nightly job that lost its reference would pass every night.
  for (const char* key : {"thresholds", "baseline"})
    if (report.contains(key) && !job.has_reference)
      throw InputError(file, std::string("/report/") + key,
                       "scores the bake against the reference, but the job has none (add \"reference\": {})");
  if (!report.contains("thresholds")) return;
  int count = 0;
  const char* const* names = metric_names(count);
  for (const auto& [key, limit] : report["thresholds"].items()) {
    const std::string where = "/report/thresholds/" + key;
    const auto first = key.find('.'), last = key.rfind('.');
    if (first == std::string::npos || last == first)
      throw InputError(file, where, "not of the form <stem>.<layer>.<metric>");
    const std::string stem = key.substr(0, first), metric = key.substr(last + 1);
    const std::string layer = key.substr(first + 1, last - first - 1);
    const auto entry =
        std::find_if(job.bakes.begin(), job.bakes.end(), [&](const BakeEntry& e) { return e.stem == stem; });
    if (entry == job.bakes.end()) {
      std::string stems;
      for (const BakeEntry& e : job.bakes) stems += (stems.empty() ? "" : ", ") + e.stem;
      throw InputError(file, where, "the job has no bake entry \"" + stem + "\" (its stems: " + stems + ")");
    }
    // A layer the entry does not write is never scored (a typo would fail the bake after it).
    const std::vector<std::string>& layers = entry_config(*entry).layers;
    if (std::find(layers.begin(), layers.end(), layer) == layers.end()) {
      std::string names;
      for (const std::string& l : layers) names += (names.empty() ? "" : ", ") + l;
      throw InputError(
          file, where,
          "bake entry \"" + stem + "\" writes no layer \"" + layer + "\" (its layers: " + names + ")");
    }
    if (std::none_of(names, names + count, [&](const char* n) { return metric == n; }))
      throw InputError(file, where, "unknown metric \"" + metric + "\"");
  }
}

// The output folder bake will create or write into: it, or its nearest existing ancestor, must be a folder
// this process may write into.
void check_output_folder(const Job& job) {
  std::error_code ec;
  fs::path p = job.output.dir;
  while (!p.empty() && !fs::exists(fs::symlink_status(p, ec)) && p.has_parent_path() && p != p.parent_path())
    p = p.parent_path();
  // As OutputStage says it: "cannot create" a folder still to be made, "cannot write into" one there.
  const std::string what =
      (p == job.output.dir ? "cannot write into " : "cannot create ") + job.output.dir.string();
  const bool exists = fs::exists(p, ec);
  if (!exists || !fs::is_directory(p, ec))
    throw InputError(
        job.file.string(), job.output.dir_key,
        what + ": " + p.string() +
            (exists                                      ? " is not a folder"
             : fs::is_symlink(fs::symlink_status(p, ec)) ? " is a link that leads to nothing (its target "
                                                           "does not exist, or its links loop)"
                                                         : " does not exist"));
  if (access(p.c_str(), W_OK | X_OK) != 0)
    throw InputError(
        job.file.string(), job.output.dir_key,
        what + ": " + p.string() + ": " + std::error_code(errno, std::generic_category()).message());
  // The folders still to be made: names the file system can hold (mkdir's ENAMETOOLONG, found now).
  const long name_max = pathconf(p.c_str(), _PC_NAME_MAX);
  for (const fs::path& part : job.output.dir.lexically_relative(p))
    if (name_max > 0 && part.native().size() > std::size_t(name_max))
      throw InputError(job.file.string(), job.output.dir_key,
                       what + ": " + std::error_code(ENAMETOOLONG, std::generic_category()).message() + " (" +
                           std::to_string(part.native().size()) + " bytes in a name, at most " +
                           std::to_string(name_max) + ")");
  // Each file is written under a temporary name beside its own (temporary_sibling, ".<name>.tmp-<pid>-<n>"
  // and the extension: at most 32 bytes more): the longest name the job writes, a texture's included, must
  // leave room for it.
  if (name_max > 0) {
    constexpr std::size_t kTemporaryBytes = 32;
    std::vector<std::pair<std::string, std::string>> names;  // file name, its key
    for (const BakeEntry& e : job.bakes)
      for (const std::string& layer : entry_config(e).layers)
        names.emplace_back(job.name + "." + e.stem + "." + layer + ".preview.png", "/name");
    for (const PlannedTexture& t : plan_textures(job))
      names.emplace_back(fs::path(t.file).filename().string(), "/output/textures");
    for (const auto& [name, key] : names)
      if (name.size() + kTemporaryBytes > std::size_t(name_max))
        throw InputError(job.file.string(), key,
                         name + ": " + std::to_string(name.size()) + " bytes, more than the " +
                             std::to_string(std::size_t(name_max) - kTemporaryBytes) +
                             " an output's name may have here (a file name holds " +
                             std::to_string(name_max) +
                             " bytes, its temporary name 32 more): a shorter job name or texture pack");
  }
  // What the bake would refuse only after baking (docs/output_folders.md): its lock names (the job's, the
  // report's for a job with a reference, the textures folder's for a job that writes textures) taken by
  // anything but a file, and a textures/ entry that is not a folder or that this process cannot write into.
  std::vector<fs::path> locks = {output_lock_file(job)};
  if (job.has_reference) locks.push_back(report_lock_file(job));
  if (textures_folder(job)) locks.push_back(textures_lock_file(job));
  for (const fs::path& lock : locks)
    if (const std::string problem = lock_name_problem(lock); !problem.empty())
      throw InputError(job.file.string(), job.output.dir_key, problem);
  check_textures_folder(job);
  // A folder where the bake moves an output or an owner record: rename(2) cannot replace it.
  std::vector<std::pair<fs::path, std::string>> folders = {{job.output.dir, job.output.dir_key}};
  if (const std::optional<fs::path> textures = textures_folder(job))
    folders.emplace_back(*textures, "/output/textures");
  for (const auto& [folder, ptr] : folders) {
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
      if (const std::string problem = output_name_problem(it->path());
          !problem.empty() && writes_in_output_folder(job, it->path(), OutputNames::moved))
        throw InputError(job.file.string(), ptr, problem);
    ec.clear();
  }
  // An input the outputs would replace (writes_in_output_folder), the job file included, and every file GDAL
  // reads through one (a VRT's sources, side files).
  std::vector<std::pair<std::string, fs::path>> inputs = {{"", job.file}};
  for (const auto& [ptr, file] : job_read_files(job)) inputs.emplace_back(ptr, file);
  for (const auto& [ptr, file] : inputs) {
    if (writes_in_output_folder(job, file))
      throw InputError(job.file.string(), ptr,
                       file.string() + " is where this job writes an output: a bake would replace it; move " +
                           "it, or give the job another name or output.dir");
  }
  // Another job's report: report.json and report.html carry no job name, so a job with a reference writes
  // them over the report of any other job baked into the same folder (docs/output_folders.md).
  check_report_owner(job);
}

std::vector<std::string> resolve_job_checks(Job& job);

}  // namespace

std::vector<std::string> resolve_job(Job& job) {
  // Whatever escapes the checks is one line too (std::bad_alloc included), never an abort.
  try {
    return resolve_job_checks(job);
  } catch (const InputError& e) {
    return {e.line()};
  } catch (const std::bad_alloc&) {
    return {printable(job.file.string() + ": not enough memory to check the job")};
  } catch (const std::exception& e) {
    return {printable(job.file.string() + ": cannot check the job: " + e.what())};
  }
}

namespace {

std::vector<std::string> resolve_job_checks(Job& job) {
  std::vector<std::string> errors;
  const std::string file = job.file.string();
  MethodContext context;
  try {
    context = job_method_context(job);
  } catch (const InputError& e) {
    errors.push_back(e.line());
    return errors;
  }
  for (BakeEntry& entry : job.bakes) {
    try {
      entry.config =
          std::make_shared<const MethodConfig>(resolve_method(entry.params, context, file, entry.pointer));
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  if (job.has_reference && errors.empty()) {
    try {
      std::vector<const MethodConfig*> entries;
      for (const BakeEntry& entry : job.bakes) entries.push_back(entry.config.get());
      job.reference_options = std::make_shared<const ReferenceOptions>(read_reference_options(
          job.doc.value("reference", nlohmann::json::object()), entries, context, file));
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  if (errors.empty()) {
    try {
      plan_textures(job);  // output.textures against the resolved layers
      check_report_settings(job, context);
      // The display and view the previews and report.html's images are shown through, named in the
      // OpenColorIO config (not found only once the first preview is written), and the config itself
      // ($OCIO) loaded whenever something is shown through it.
      if (!job.output.preview_display.empty() || !job.output.preview_view.empty())
        check_display_view(job.output.preview_display, job.output.preview_view,
                           InputSite{file, "/output/preview_display"},
                           InputSite{file, "/output/preview_view"});
      else if (job.output.previews || job.has_reference) {
        const InputSite site{file, job.output.previews ? "/output/previews" : "/reference"};
        check_display_view("", "", site, site);
      }
      check_output_folder(job);
    } catch (const InputError& e) {
      errors.push_back(e.line());
    }
  }
  return errors;
}

}  // namespace

bool writes_in_output_folder(const Job& job, const fs::path& file, OutputNames names) {
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(fs::absolute(job.output.dir), ec);
  if (ec) return false;
  const fs::path real = fs::weakly_canonical(fs::absolute(file), ec);
  if (ec) return false;
  const std::string n = real.filename().string();
  const bool kept = names == OutputNames::kept;
  if (real.parent_path() == dir / "textures") {
    if (kept)
      return n.rfind(job.name + ".", 0) == 0 || n == textures_lock_file(job).filename() ||
             n == textures_owner_record(job).filename();
    if (!textures_folder(job)) return false;
    const std::vector<PlannedTexture> textures = plan_textures(job);
    return n == textures_owner_record(job).filename() ||
           std::any_of(textures.begin(), textures.end(),
                       [&](const PlannedTexture& t) { return fs::path(t.file).filename() == n; });
  }
  // A tile task's files (cli/tile_command.hpp) are kept names; a bake moves none of them into place.
  if (real.parent_path() == dir / "tiles")
    return kept && (n.rfind(tile_file_prefix(job), 0) == 0 || n == tiles_lock_file(job).filename() ||
                    n == tiles_owner_record(job).filename());
  // A shard task's files (farm/shard_plan.hpp), kept as a tile task's are.
  if (real.parent_path() == dir / "shards")
    return kept && (is_shard_file_name(job, n) || n == shards_lock_file(job).filename() ||
                    n == shards_owner_record(job).filename());
  if (real.parent_path() != dir) return false;
  if (n == owner_record(job).filename() ||
      ((kept || job.has_reference) && (n == "report.json" || n == "report.html")))
    return true;
  if (kept && (n == output_lock_file(job).filename() || n == report_lock_file(job).filename())) return true;
  const auto ends_with = [&n](const std::string& tail) {
    return n.size() >= tail.size() && n.compare(n.size() - tail.size(), tail.size(), tail) == 0;
  };
  std::vector<std::string> stems;
  if (kept || job.has_reference) stems.push_back("reference");
  for (const BakeEntry& e : job.bakes) stems.push_back(e.stem);
  for (const std::string& stem : stems) {
    const std::string at = job.name + "." + stem + ".";
    if (n == job.output_path(stem, ".exr").filename().string() ||
        (n.rfind(at, 0) == 0 && (((kept || job.output.previews) && ends_with(".preview.png")) ||
                                 ((kept || job.output.geotiff) && ends_with(".tif")))))
      return true;
  }
  return false;
}

const MethodConfig& entry_config(const BakeEntry& entry) {
  if (!entry.config)
    throw std::logic_error("bake entry " + entry.pointer + " was not resolved (resolve_job)");
  return *entry.config;
}

LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc) {
  const MethodConfig& config = entry_config(entry);
  return config.method->bake(scene, config, rc);
}

const ReferenceOptions& job_reference_options(const Job& job) {
  if (!job.reference_options) throw std::logic_error("the job's reference was not resolved (resolve_job)");
  return *job.reference_options;
}

}  // namespace hfbake
