#include "cli/tile_command.hpp"

#include <malloc.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/scene_inputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/version.hpp"
#include "core/error.hpp"
#include "io/georaster_input.hpp"
#include "io/geotiff_output.hpp"
#include "job/content_hash.hpp"
#include "methods/method_table.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void refuse(const Job& job, const std::string& pointer, const std::string& what) {
  throw InputError(job.file.string(), pointer, what);
}

// The halo of the job's entries: the largest of their reaches, in texels of the shorter side (check_tiled_job
// has made sure each is bounded).
int job_halo(const Job& job) {
  const std::array<double, 2> sides = job_texel_sides(job);
  const double texel = std::min(sides[0], sides[1]);
  int halo = 0;
  for (const BakeEntry& entry : job.bakes) {
    const MethodConfig& config = entry_config(entry);
    const std::optional<int> h = halo_texels(config.method->reach(config), texel);
    if (!h)
      refuse(
          job, entry.pointer,
          "reads heights without a bound: it cannot be baked in tiles (p1 and sun need a far_field; hbao a "
          "radius of bounded support or a max_distance)");
    halo = std::max(halo, *h);
  }
  return halo;
}

// The heights of `window` as a field of its own (as stored: complete_scene applies scale and offset), after
// the nodata rule of a tiled bake: a texel without a valid height is an error naming it in the raster.
HeightField read_window(const Job& job, const GeoHeightBand& band, const RasterWindow& window) {
  Plane plane = read_georaster_window(band.file, band.band, window.x0, window.y0, window.width, window.height,
                                      {job.file.string(), "/height/image"});
  const nlohmann::json& h = job.doc["height"];
  // The job's and the file's NoData values; NaN (equal to nothing) when absent.
  const float job_nodata = h.contains("nodata_value") ? h["nodata_value"].get<float>() : NAN;
  const float file_nodata = band.nodata ? float(*band.nodata) : NAN;
  for (std::size_t t = 0; t < plane.values.size(); ++t) {
    const float z = plane.values[t];
    if (std::isfinite(z) && z != job_nodata && z != file_nodata) continue;
    const std::size_t i = std::size_t(window.x0) + t % std::size_t(window.width);
    const std::size_t j = std::size_t(window.y0) + t / std::size_t(window.width);
    refuse(job, "/height/image",
           band.file.string() + ": texel (" + std::to_string(i) + ", " + std::to_string(j) +
               ") has no valid height; a tiled bake does not fill holes: fill them first "
               "(gdal_fillnodata.py) or bake the raster whole with \"nodata\": \"fill\"");
  }
  HeightField field;
  field.width = window.width;
  field.height = window.height;
  const std::array<double, 2> sides = job_texel_sides(job);  // a geographic raster's are rectangles
  field.texel_size = sides[0];
  if (sides[1] != sides[0]) field.texel_size_y = sides[1];
  field.wrap = Wrap::clamp;
  field.z = std::move(plane.values);
  return field;
}

// The cell sides of the coarse copies of the whole raster the job's entries walk (MethodInfo::far_cell),
// each once, and the bytes they hold.
std::vector<int> job_far_cells(const Job& job) {
  std::vector<int> cells;
  for (const BakeEntry& entry : job.bakes) {
    const MethodConfig& config = entry_config(entry);
    const int cell = config.method->far_cell ? config.method->far_cell(config) : 0;
    if (cell > 0 && std::find(cells.begin(), cells.end(), cell) == cells.end()) cells.push_back(cell);
  }
  return cells;
}

std::size_t coarse_copies_bytes(const Job& job, int width, int height) {
  double bytes = 0;
  for (const int cell : job_far_cells(job)) bytes += coarse_bytes(width, height, cell);
  return std::size_t(bytes);
}

// The rows of a run read for the coarse copies: as many as `budget` holds, between 1 and 256.
int strip_rows(int width, int height, std::size_t budget) {
  return int(std::clamp<std::size_t>(budget / (sizeof(float) * std::size_t(width)), 1,
                                     std::size_t(std::min(height, 256))));
}

std::string tiles_text(const TilePlan& plan) {
  return std::to_string(plan.columns * plan.rows) + " tiles (" + std::to_string(plan.columns) + " x " +
         std::to_string(plan.rows) + ") of " + std::to_string(plan.tile) + "^2 texels with a halo of " +
         std::to_string(plan.halo) +
         (plan.kept_bytes > 0 ? ", beside coarse copies of the raster of " +
                                    std::to_string((plan.kept_bytes + (1 << 20) - 1) >> 20) + " MiB"
                              : std::string());
}

// The refusal of the file at tile k's name when it is not that tile of this job and plan, saying what it is:
// missing, not a regular file (a folder, a FIFO), empty, or a raster of something else.
std::string not_tile(const fs::path& file, std::size_t k, const TilePlan& plan) {
  const std::string tile = "tile " + std::to_string(k);
  std::error_code ec;
  if (!fs::exists(file, ec)) return "is missing: bake its tile task (bake --tiles --tile-task)";
  std::string why;
  const int fd = open_regular_file(file, why);
  if (fd < 0)
    return "cannot read " + tile + ": " + why + ": remove it and bake its tile task again (--tile-task)";
  struct stat st {};
  const bool empty = fstat(fd, &st) == 0 && st.st_size == 0;
  close(fd);
  if (empty) return "is empty, not " + tile + ": bake its tile task again (--tile-task)";
  return "is not " + tile + " of this job (its heights and parameters) and plan (" + tiles_text(plan) +
         "): bake it again with --tile-task";
}

// Bakes tile `k` of the plan: the tile's heights as a field of their own, then each entry through the method
// table; sink(entry index, its layers, the interior's offset in them) gets each entry's layers.
// `coarse`: the raster's coarse copies (coarse_copies), handed to every tile.
template <class Sink>
void bake_tile(const Job& job, const GeoHeightBand& band, const TilePlan& plan, std::size_t k,
               const std::vector<std::shared_ptr<const CoarseHeights>>& coarse,
               const std::atomic<bool>& cancel, const std::function<void(double)>& progress,
               std::vector<double>& seconds, Sink&& sink) {
  if (cancel.load()) throw Cancelled();
  const Tile& tile = plan.tiles[k];
  // The raster's georeference but its holes (a tiled bake refuses holes): its CRS (the Earth's curvature from
  // its ellipsoid) and its site (sun's place, a geographic raster's frame), the whole bake's whatever the
  // tile.
  Georeference tile_geo = band.georeference;
  std::vector<std::uint8_t>().swap(tile_geo.holes);
  Scene scene = complete_scene(job, read_window(job, band, tile.read), tile_geo, band.source);
  const int ox = tile.interior.x0 - tile.read.x0, oy = tile.interior.y0 - tile.read.y0;
  scene.window = {tile.read.x0, tile.read.y0, coarse, {ox, oy, tile.interior.width, tile.interior.height}};
  for (std::size_t e = 0; e < job.bakes.size(); ++e) {
    const BakeEntry& entry = job.bakes[e];
    const MethodConfig& config = entry_config(entry);
    RunControl rc;
    rc.cancel = &cancel;
    rc.progress = [&](double f) { progress((double(e) + f) / double(job.bakes.size())); };
    const auto t0 = std::chrono::steady_clock::now();
    LayerSet layers = config.method->bake(scene, config, rc);
    seconds[e] += seconds_since(t0);
    check_layers_finite(entry.stem, layers);
    sink(e, layers, ox, oy);
  }
}

// What a tile file of entry `e` must say it belongs to (its HFBAKE_TILE_OF item): the job (its name and
// content: job_content_hash, the document and its input files' bytes, as a shard's), the plan and the
// entry's resolved parameters.
std::string tile_identity(const Job& job, const std::string& content, const TilePlan& plan, std::size_t e) {
  return job.name + " " + content + "; " + tiles_text(plan) + "; " + job.bakes[e].stem + " " +
         entry_config(job.bakes[e]).resolved.dump();
}

// The checksum of a tile file's values (each texel's channels in turn) that its HFBAKE_TILE_SUM item holds:
// it finds damage, not a forger (docs/large-fields.md), as a shard's does.
std::string tile_checksum(const std::vector<float>& values) {
  ContentHash h;
  h.add(std::string_view(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float)));
  return h.hex();
}

// <output dir>/tiles/<name>+tile-<k>.<stem>.<layer>.tif: tile k's interior of one layer, from a tile task
// (cli/outputs.hpp tiles_folder: no other job's file has that name).
fs::path tile_file(const Job& job, std::size_t k, const std::string& stem, const std::string& layer) {
  return tiles_folder(job) / (tile_file_prefix(job) + std::to_string(k) + "." + stem + "." + layer + ".tif");
}

// GeoTIFF metadata of an output of entry `e`.
GeoTiffOptions output_options(const Job& job, const OutputStage& stage, const TilePlan& plan, std::size_t e) {
  GeoTiffOptions tiff;
  tiff.metadata = stage.geotiff_metadata({{"hfbake:version", hfbake_version()},
                                          {"hfbake:job", job.name},
                                          {"hfbake:method", job.bakes[e].method},
                                          {"hfbake:parameters", entry_config(job.bakes[e]).resolved.dump()},
                                          {"hfbake:tiles", tiles_text(plan)}});
  return tiff;
}

// A tile task's file holds its entry's attributes as metadata items kTileAttribute<n>, "<key>=<value>".
const std::string kTileAttribute = "HFBAKE_TILE_ATTRIBUTE_";

// A far field's certified bound, the attribute "hfbake:<method>:far_field_bound" (relief, p1, sun): the
// largest of the tiles' is the whole bake's.
std::string far_bound_key(const std::string& method) {
  return "hfbake:" + method + ":far_field_bound";
}

// A tile's attributes into its entry's: each kept as the first tile gave it, the far-field bound as the
// largest of the tiles'.
void merge_attributes(std::vector<std::pair<std::string, std::string>>& into,
                      const std::vector<std::pair<std::string, std::string>>& from,
                      const std::string& method) {
  for (const auto& kv_from : from) {
    const std::string &key = kv_from.first, &value = kv_from.second;  // named: lambdas capture them
    auto at = std::find_if(into.begin(), into.end(), [&](const auto& kv) { return kv.first == key; });
    if (at == into.end()) {
      into.emplace_back(key, value);
    } else if (key == far_bound_key(method) && std::stod(value) > std::stod(at->second)) {
      at->second = value;
    }
  }
}

// The tiles of tile task `task`: [I T / N, (I + 1) T / N) of the plan's T.
std::pair<std::size_t, std::size_t> task_tiles(const TilePlan& plan, ShardId task) {
  const std::size_t t = plan.tiles.size();
  return {t * std::size_t(task.index) / std::size_t(task.count),
          t * std::size_t(task.index + 1) / std::size_t(task.count)};
}

// The raster's coarse copies the job's entries walk, from one pass of windowed reads of `rows` rows at a
// time (never the whole raster in memory), under the tiled bake's nodata rule.
std::vector<std::shared_ptr<const CoarseHeights>> coarse_copies(const Job& job, const GeoHeightBand& band,
                                                                int rows, const std::atomic<bool>& cancel,
                                                                const std::function<void(double)>& progress) {
  std::vector<CoarseHeights> copies;
  for (const int cell : job_far_cells(job))
    copies.push_back(empty_coarse(band.width, band.height, cell, Wrap::clamp));
  if (copies.empty()) return {};
  for (int y = 0; y < band.height; y += rows) {
    if (cancel.load()) throw Cancelled();
    const int n = std::min(rows, band.height - y);
    HeightField strip = read_window(job, band, RasterWindow{0, y, band.width, n});
    to_world_heights(job, strip.z.data(), strip.z.size());  // as the tiles' own heights (complete_scene)
    for (CoarseHeights& g : copies) add_coarse_rows(g, strip.z.data(), y, n);
    progress(double(y + n) / band.height);
  }
  std::vector<std::shared_ptr<const CoarseHeights>> out;
  for (CoarseHeights& g : copies) out.push_back(std::make_shared<const CoarseHeights>(std::move(g)));
  return out;
}

}  // namespace

void check_tiled_job(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (!h.contains("image") || !georaster_height_band(job))
    refuse(job, h.contains("image") ? "/height/image" : "/height",
           "a tiled bake reads a georeferenced raster through GDAL (GeoTIFF, COG, VRT, ...): this job's "
           "heights are not one");
  if (h.value("wrap", "clamp") == "repeat")
    refuse(job, "/height/wrap",
           "a tiled bake bakes clamp fields only (a repeat field's tiles wrap around it)");
  if (h.value("nodata", "error") == "fill")
    refuse(job, "/height/nodata",
           "a tiled bake does not fill holes (each tile would fill its own): fill them first "
           "(gdal_fillnodata.py)");
  const nlohmann::json surface = job.doc.value("surface", nlohmann::json::object());
  for (const char* key : {"albedo", "emission"})
    if (surface.contains(key) && surface[key].is_object())
      refuse(job, std::string("/surface/") + key + "/image",
             "a tiled bake takes a constant albedo and emission, not an image");
  if (job.has_reference)
    refuse(job, "/reference", "a tiled bake has no reference: bake a window of the raster whole to check it");
  if (job.doc.contains("output") && job.doc["output"].contains("textures"))
    refuse(job, "/output/textures", "a tiled bake writes GeoTIFFs only, no textures");
  if (!job.output.geotiff)
    refuse(job, "/output/geotiff", "a tiled bake writes Cloud-Optimised GeoTIFFs only: set it to true");
  for (const BakeEntry& entry : job.bakes) {
    const MethodConfig& config = entry_config(entry);
    if (!config.method->reach)
      refuse(job, entry.pointer + "/method",
             entry.method +
                 " reads heights from the whole field: a tiled bake takes the methods with a bounded reach "
                 "(relief, p1 and sun with a far_field, hbao with a radius or max_distance)");
  }
  job_halo(job);
}

namespace {

// The estimate of a bake of a w x h read window of a tiled bake (its layers written as tile files).
std::size_t window_bytes(const Job& job, int w, int h) {
  return estimate_peak_bytes(job, FieldSize{.width = w, .height = h, .tile = true, .georaster = true});
}

// The estimate of a tile of interior side `side` read with `halo` on a raster of width x height.
std::size_t tile_window_bytes(const Job& job, int width, int height, int side, int halo) {
  return window_bytes(job, int(std::min<std::int64_t>(width, std::int64_t(side) + 2 * std::int64_t(halo))),
                      int(std::min<std::int64_t>(height, std::int64_t(side) + 2 * std::int64_t(halo))));
}

// What the process holds while the COG of the job's widest layer is written (after the tiles): the process
// itself and the COG driver's buffers of every band, beside GDAL's cache; and that layer's name and band
// count, for a refusal.
struct CogFinish {
  std::size_t bytes = 0;
  std::string layer;
  int bands = 0;
};
CogFinish cog_finish(const Job& job, int width, int height) {
  CogFinish f;
  for (const BakeEntry& entry : job.bakes) {
    const MethodConfig& config = entry_config(entry);
    for (const std::string& name : config.layers)
      if (const int n = layer_channel_count(name, config.directions); n > f.bands)
        f.bands = n, f.layer = name;
  }
  f.bytes = estimate_process_bytes(
                job, FieldSize{.width = width, .height = height, .tile = true, .georaster = true}) +
            std::size_t(cog_band_bytes(width, height) * f.bands);
  return f;
}

}  // namespace

std::size_t tiled_peak_bytes(const Job& job, const TilePlan& plan) {
  return std::max(tile_window_bytes(job, plan.width, plan.height, plan.tile, plan.halo),
                  cog_finish(job, plan.width, plan.height).bytes) +
         kTiledGdalCacheBytes + plan.kept_bytes;
}

TilePlan plan_job_tiles(const Job& job, std::size_t budget, std::optional<int> tile_size) {
  const std::optional<GeoHeightBand> band = georaster_height_band(job);
  if (!band) refuse(job, "/height", "a tiled bake reads a georeferenced raster through GDAL");
  const int halo = job_halo(job);
  // The coarse copies of the whole raster stay while tiling: the tiles get what they leave.
  const std::size_t coarse = coarse_copies_bytes(job, band->width, band->height);
  const std::size_t tile_budget =
      budget > kTiledGdalCacheBytes + coarse ? budget - kTiledGdalCacheBytes - coarse : 0;
  if (coarse > 0 && tile_budget == 0)
    refuse(
        job, "/height",
        "the far fields' coarse copies of the raster (about " +
            std::to_string((coarse + (1u << 20) - 1) >> 20) + " MiB) and GDAL's block cache (" +
            std::to_string(kTiledGdalCacheBytes >> 20) +
            " MiB) leave nothing of the memory budget for the tiles (--memory-limit, or a larger far_field "
            "cell)");
  // The COGs are written after the tiles, a layer at a time: the widest one's bands must fit too.
  const auto check_cog = [&] {
    const CogFinish f = cog_finish(job, band->width, band->height);
    if (f.bytes > tile_budget)
      refuse(job, "/output/geotiff",
             "writing the COG of layer " + f.layer + " (" + std::to_string(f.bands) +
                 (f.bands == 1 ? " band" : " bands") + ") holds about " +
                 std::to_string((f.bytes + (1u << 20) - 1) >> 20) +
                 " MiB with the process, beside GDAL's block cache: more than the " +
                 std::to_string(tile_budget >> 20) +
                 " MiB the memory budget leaves (--memory-limit, or fewer directions)");
  };
  auto peak = [&](int side) { return tile_window_bytes(job, band->width, band->height, side, halo); };
  auto too_large = [&](int side, const std::string& knob) {
    refuse(
        job, "/height",
        "a tile of " + std::to_string(side) + "^2 texels with its halo of " + std::to_string(halo) +
            " needs about " + std::to_string(peak(side) >> 20) + " MiB, more than the " +
            std::to_string(tile_budget >> 20) + " MiB the memory budget leaves" +
            (coarse > 0 ? " beside the far fields' coarse copies (" + std::to_string(coarse >> 20) + " MiB)"
                        : std::string()) +
            " (" + knob + ")");
  };
  if (tile_size) {
    if (peak(*tile_size) > tile_budget) too_large(*tile_size, "--memory-limit, or a smaller --tile-size");
    check_cog();
    TilePlan plan = plan_tiles(band->width, band->height, *tile_size, halo);
    plan.kept_bytes = coarse;
    return plan;
  }
  const std::optional<int> side =
      tile_side_for_budget(band->width, band->height, halo, tile_budget, 256,
                           [&job](int w, int h) { return window_bytes(job, w, h); });
  if (!side) too_large(256, "--memory-limit");
  check_cog();
  TilePlan plan = plan_tiles(band->width, band->height, *side, halo);
  plan.kept_bytes = coarse;
  return plan;
}

std::string validate_tiled(const Job& job, std::size_t budget, std::optional<int> tile_size) {
  check_tiled_job(job);
  const TilePlan plan = plan_job_tiles(job, budget, tile_size);
  const GeoHeightBand band = *georaster_height_band(job);
  GdalCacheLimit cache(kTiledGdalCacheBytes);
  for (const Tile& tile : plan.tiles) read_window(job, band, tile.interior);
  return tiles_text(plan);
}

void bake_tiled(const Job& job, Progress& progress, const std::atomic<bool>& cancel, JobOutcome& outcome,
                const BakeOptions& options, std::size_t budget) {
  check_tiled_job(job);
  const TilePlan plan = plan_job_tiles(job, budget, options.tile_size);
  const GeoHeightBand band = *georaster_height_band(job);
  GdalCacheLimit cache(kTiledGdalCacheBytes);
  std::vector<double> seconds(job.bakes.size(), 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  // The job's name in tiles/: claimed by its tasks (one job file's tiles of that name), checked by its merge.
  // A task's windows are checked for holes first, so a refused task claims nothing (`validate --tiles`
  // checks every window; a task reads only its own).
  if (options.tile_task) {
    const auto range = task_tiles(plan, *options.tile_task);
    for (std::size_t k = range.first; k < range.second; ++k) read_window(job, band, plan.tiles[k].interior);
    claim_tiles_folder(job, options.overwrite);
  }
  if (options.merge) check_tiles_folder(job, options.overwrite);
  // The far fields' coarse copies of the whole raster, read in runs of rows within what the tiles will
  // take (the plan left room for the copies beside them).
  std::vector<std::shared_ptr<const CoarseHeights>> coarse;
  if (!options.merge && !job_far_cells(job).empty()) {
    const std::size_t left =
        budget - kTiledGdalCacheBytes - coarse_copies_bytes(job, band.width, band.height);
    progress.begin(job.name, "coarse copy");
    coarse = coarse_copies(job, band, strip_rows(band.width, band.height, left), cancel,
                           [&](double f) { progress.update(job.name, "coarse copy", f); });
    progress.end(job.name, "coarse copy", seconds_since(t0));
  }

  // Tile files name the job's content: a merge takes none baked from other heights or another job.
  const std::string content = options.tile_task || options.merge ? job_content_hash(job) : std::string();
  if (options.tile_task) {  // a task's tiles, each layer's interior into its tile file
    const auto range = task_tiles(plan, *options.tile_task);
    const std::size_t first = range.first, end = range.second;  // named: the progress lambda captures them
    progress.message(job.name + ": tiles " + std::to_string(first) + ".." + std::to_string(end) + " of " +
                     tiles_text(plan));
    const fs::path folder = tiles_folder(job);
    // Held from here (core/safe_file.hpp HeldFolder): a link planted at tiles/ while the task runs is never
    // written through.
    const HeldFolder held(folder, /*follow_link=*/false);
    if (!held.held())
      throw InputError(job.file.string(), job.output.dir_key,
                       folder.string() + " is not a folder (a link?): tiles are written inside " +
                           job.output.dir.string() + " only");
    for (const fs::path& p : remove_stale_temporaries(folder))
      progress.message(job.name + ": removed " + p.string() + " (left by a process that no longer runs)");
    progress.begin(job.name, "tiles");
    for (std::size_t k = first; k < end; ++k) {
      const Tile& tile = plan.tiles[k];
      bake_tile(
          job, band, plan, k, coarse, cancel,
          [&](double f) {
            progress.update(job.name, "tiles", (double(k - first) + f) / double(end - first));
          },
          seconds,
          [&](std::size_t e, const LayerSet& layers, int ox, int oy) {
            Georeference geo = band.georeference;
            geo.geotransform[0] += tile.interior.x0 * geo.geotransform[1];
            geo.geotransform[3] += tile.interior.y0 * geo.geotransform[5];
            GeoTiffOptions tiff;
            tiff.metadata = {
                {"HFBAKE_TILE_OF", std::to_string(k) + " of " + tile_identity(job, content, plan, e)}};
            // The entry's attributes, "<key>=<value>" each, for the merge (merge_attributes).
            int n = 0;
            for (const auto& [key, value] : layers.attributes)
              tiff.metadata.emplace_back(kTileAttribute + std::to_string(n++), key + "=" + value);
            for (const Layer& layer : layers.layers) {
              const std::size_t nc = std::size_t(layer.channel_count());
              LayerSet part;
              part.width = tile.interior.width;
              part.height = tile.interior.height;
              std::vector<float> data(std::size_t(part.width) * std::size_t(part.height) * nc);
              for (int j = 0; j < part.height; ++j) {
                const float* row = layer.data.data() +
                                   (std::size_t(oy + j) * std::size_t(layers.width) + std::size_t(ox)) * nc;
                std::copy(row, row + std::size_t(part.width) * nc,
                          data.begin() + std::ptrdiff_t(std::size_t(j) * std::size_t(part.width) * nc));
              }
              // Which layer it is, and its values' checksum: a merge refuses another layer's file of the
              // same tile and a damaged one.
              GeoTiffOptions own = tiff;
              own.metadata[0].second += "; layer " + layer.name;
              own.metadata.emplace_back("HFBAKE_TILE_SUM", tile_checksum(data));
              const Layer& l = part.adopt(layer.name, layer.channels, std::move(data));
              write_geotiff(held.path() / tile_file(job, k, job.bakes[e].stem, layer.name).filename(), part,
                            l, geo, own);
            }
          });
    }
    progress.end(job.name, "tiles", seconds_since(t0));
    for (std::size_t e = 0; e < job.bakes.size(); ++e)
      outcome.methods[job.bakes[e].stem] = {
          {"method", job.bakes[e].method}, {"seconds", seconds[e]}, {"tiles", end - first}};
    return;
  }

  OutputStage stage(job, options.overwrite);
  for (const std::string& line : stage.notes()) progress.message(job.name + ": " + line);
  stage.set_georeference(band.georeference);
  progress.message(job.name + ": " + std::to_string(band.width) + "x" + std::to_string(band.height) + " in " +
                   tiles_text(plan));
  // One work file per entry and layer, made when the first tile gives its channels (or, merging, from the
  // entry's layers).
  struct Output {
    std::string file;  // <name>.<stem>.<layer>.tif
    std::unique_ptr<TiledGeoTiff> writer;
  };
  std::map<std::pair<std::size_t, std::string>, Output> outputs;
  // Each entry's attributes (merge_attributes): what its COGs carry, as a whole bake's do.
  std::vector<std::vector<std::pair<std::string, std::string>>> attributes(job.bakes.size());
  auto output = [&](std::size_t e, const std::string& layer,
                    const std::vector<std::string>& channels) -> Output& {
    Output& out = outputs[{e, layer}];
    if (!out.writer) {
      out.file = job.name + "." + job.bakes[e].stem + "." + layer + ".tif";
      out.writer = std::make_unique<TiledGeoTiff>(stage.folder() / ("." + out.file + ".work"), plan.width,
                                                  plan.height, layer, channels, band.georeference,
                                                  output_options(job, stage, plan, e));
    }
    return out;
  };
  progress.begin(job.name, "tiles");
  for (std::size_t k = 0; k < plan.tiles.size(); ++k) {
    const Tile& tile = plan.tiles[k];
    auto tile_progress = [&](double f) {
      progress.update(job.name, "tiles", (double(k) + f) / double(plan.tiles.size()));
    };
    if (options.merge) {  // the tile tasks' files, each checked against the plan before it is taken
      if (cancel.load()) throw Cancelled();
      for (std::size_t e = 0; e < job.bakes.size(); ++e) {
        const MethodConfig& config = entry_config(job.bakes[e]);
        for (const std::string& name : config.layers) {
          const fs::path file = tile_file(job, k, job.bakes[e].stem, name);
          const int nc = layer_channel_count(name, config.directions);
          const std::string expected =
              std::to_string(k) + " of " + tile_identity(job, content, plan, e) + "; layer " + name;
          const std::optional<GeoRasterInfo> info = probe_georaster(file);
          if (!info || georaster_metadata_item(file, "HFBAKE_TILE_OF") != expected ||
              info->width != tile.interior.width || info->height != tile.interior.height || info->bands != nc)
            throw InputError(file.string(), "", not_tile(file, k, plan));
          if (name ==
              config.layers.front()) {  // the entry's attributes, the same in each of its layers' files
            std::vector<std::pair<std::string, std::string>> tile_attributes;
            for (int n = 0;; ++n) {
              const std::string item = georaster_metadata_item(file, kTileAttribute + std::to_string(n));
              const std::size_t eq = item.find('=');
              if (eq == std::string::npos) break;
              tile_attributes.emplace_back(item.substr(0, eq), item.substr(eq + 1));
            }
            merge_attributes(attributes[e], tile_attributes, job.bakes[e].method);
          }
          std::vector<std::string> channels;
          std::vector<float> texels(std::size_t(info->width) * std::size_t(info->height) * std::size_t(nc));
          for (int c = 0; c < nc; ++c) {
            const Plane plane =
                read_georaster_window(file, c, 0, 0, info->width, info->height, {});  // names the file
            for (std::size_t t = 0; t < plane.values.size(); ++t)
              texels[t * std::size_t(nc) + std::size_t(c)] = plane.values[t];
            channels.push_back(geotiff_band_channel(name, info->band_names[std::size_t(c)]));
          }
          if (tile_checksum(texels) != georaster_metadata_item(file, "HFBAKE_TILE_SUM"))
            throw InputError(file.string(), "",
                             "is damaged: its values are not those its tile task wrote (their checksum "
                             "differs): bake it again with --tile-task");
          output(e, name, channels)
              .writer->write(tile.interior.x0, tile.interior.y0, tile.interior.width, tile.interior.height,
                             texels.data(), std::size_t(tile.interior.width));
        }
      }
      tile_progress(1);
      continue;
    }
    bake_tile(job, band, plan, k, coarse, cancel, tile_progress, seconds,
              [&](std::size_t e, const LayerSet& layers, int ox, int oy) {
                merge_attributes(attributes[e], layers.attributes, job.bakes[e].method);
                for (const Layer& layer : layers.layers) {
                  const std::size_t nc = std::size_t(layer.channel_count());
                  const float* first = layer.data.data() +
                                       (std::size_t(oy) * std::size_t(layers.width) + std::size_t(ox)) * nc;
                  output(e, layer.name, layer.channels)
                      .writer->write(tile.interior.x0, tile.interior.y0, tile.interior.width,
                                     tile.interior.height, first, std::size_t(layers.width));
                }
              });
  }
  progress.end(job.name, "tiles", seconds_since(t0));
  progress.begin(job.name, "cog");
  // The COGs start from the process alone: GDAL's block cache emptied (the work files' last blocks written)
  // and what the tiles freed given back to the system, so each layer's COG holds the process, its bands'
  // buffers and the cache it fills again (tiled_peak_bytes), not those beside what the tiles left.
  { const GdalCacheLimit empty(0); }
  malloc_trim(0);
  const auto t2 = std::chrono::steady_clock::now();
  for (auto& [key, out] : outputs) {
    if (cancel.load()) throw Cancelled();
    for (const auto& [name, value] : stage.geotiff_metadata(attributes[key.first]))
      out.writer->set_metadata(name, value);
    out.writer->finish(stage.folder() / out.file);
    out.writer.reset();
    stage.adopt(out.file);
  }
  progress.end(job.name, "cog", seconds_since(t2));
  for (std::size_t e = 0; e < job.bakes.size(); ++e)
    outcome.methods[job.bakes[e].stem] = {
        {"method", job.bakes[e].method}, {"seconds", seconds[e]}, {"tiles", plan.tiles.size()}};
  outcome.outputs = stage.commit();
  for (const fs::path& p : outcome.outputs) progress.message(job.name + ": wrote " + p.string());
  for (const fs::path& p : stage.removed())
    progress.message(job.name + ": removed " + p.string() +
                     " (its previous bake's, not written by this one)");
}

}  // namespace hfbake
