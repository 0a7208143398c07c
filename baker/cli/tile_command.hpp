// `hfbake bake --tiles`: a georeferenced raster baked in spatial tiles, so its size is bounded by the disk
// rather than the memory budget (docs/large-fields.md). Each tile's heights are read as a window of the
// raster grown by a halo (farm/tile_plan.hpp) that covers every method's reach (MethodInfo::reach), baked
// through the method table as a field of its own, and its interior written into each layer's work file;
// when every tile is baked the work files become the job's Cloud-Optimised GeoTIFFs,
// <name>.<stem>.<layer>.tif, the same texels the whole bake writes. Nothing else is written.
#pragma once

#include <atomic>
#include <cstddef>
#include <optional>
#include <string>

#include "cli/bake_command.hpp"
#include "cli/job_outcome.hpp"
#include "cli/progress.hpp"
#include "farm/tile_plan.hpp"
#include "job/manifest.hpp"

namespace hfbake {

// Budget kept for GDAL's block cache while a tiled bake runs (set to this for its duration).
inline constexpr std::size_t kTiledGdalCacheBytes = std::size_t(64) << 20;

// What a tiled bake refuses, before anything is read or written: InputError naming the job file and the
// key for heights not read through GDAL, a repeat field, holes to fill, an albedo or emission image, a
// reference, textures, output.geotiff off, and an entry whose method has no bounded reach.
void check_tiled_job(const Job& job);

// The job's tile plan: the halo covers the largest reach of its entries; the interiors' side is
// `tile_size` when given, else the largest multiple of 256; either way its read window's memory estimate
// (cli/scene_loader.hpp estimate_peak_bytes) must fit `budget` less kTiledGdalCacheBytes: InputError at
// /height otherwise (naming the side, the halo and the estimate).
TilePlan plan_job_tiles(const Job& job, std::size_t budget, std::optional<int> tile_size);

// The most a tiled bake of `plan` holds at once: its largest tile's read window baked (the estimate
// plan_job_tiles fits), the GDAL block cache (kTiledGdalCacheBytes) and the plan's kept bytes. What each
// task of `hfbake slurm --tiles` asks for.
std::size_t tiled_peak_bytes(const Job& job, const TilePlan& plan);

// What `validate --tiles` checks of a tiled bake: check_tiled_job, the plan, and every texel of the raster
// read (a window at a time) under the tiled bake's nodata rule. Returns the plan in words ("16 tiles (4 x 4)
// of 4864^2 texels with a halo of 6").
std::string validate_tiled(const Job& job, std::size_t budget, std::optional<int> tile_size);

// Bakes `job` in tiles (check_tiled_job first) into its output folder, staged like bake_job's outputs:
// the COGs appear whole, or nothing does. `options`: --tile-size (else the plan from `budget`),
// --overwrite, and the farm's two halves:
//   - tile_task I/N: only tiles [I T / N, (I + 1) T / N) of the plan's T, each layer's interior written
//     as <output dir>/tiles/<name>+tile-<k>.<stem>.<layer>.tif (a GeoTIFF naming the tile, the job, the plan
//     and the entry's parameters in its HFBAKE_TILE_OF item), nothing staged; the job's name in tiles/
//     claimed first (cli/outputs.hpp claim_tiles_folder: InputError when another job file's tiles hold it);
//   - merge: the COGs from those files instead of baking, tiles/ checked first (check_tiles_folder), each
//     file checked against the plan (missing, of another plan or job, another size or band count: InputError
//     naming it) before it is taken.
// The tasks and the merge must make the same plan: give them the same --tile-size.
void bake_tiled(const Job& job, Progress& progress, const std::atomic<bool>& cancel, JobOutcome& outcome,
                const BakeOptions& options, std::size_t budget);

}  // namespace hfbake
