// The file-reading half of building a Scene: the height image, the albedo and emission maps and the
// lighting. Kept apart from scene_loader.cpp so the loader's logic (procedural fields, scaling, normals)
// does not pull in the image libraries' headers. Every problem is an InputError naming the job file,
// the JSON pointer and, where there is one, the image.
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/scene_loader.hpp"

namespace hfbake {

// Every file a bake of the job reads, each with the JSON pointer of the input that names it: the files its
// document names (job_input_files), each followed by the other files GDAL reads through it (raster_files: a
// VRT's sources, side files such as .aux.xml and .msk). What the job's outputs never replace, and what its
// identity hashes.
std::vector<std::pair<std::string, std::filesystem::path>> job_read_files(const Job& job);

// The job's identity for the farm (shards, stage files, tiles) and the reference checkpoints: its document
// and the bytes of every file job_read_files names (job/content_hash.hpp content_hash_of).
std::string job_content_hash(const Job& job);

// The size of the height image from its header (nothing decoded). A georeferenced raster (read through
// GDAL) is checked here already, so validate refuses what bake refuses: a rotated geotransform, non-square
// pixels in a projected CRS, a job texel_size other than the pixel size, a geographic raster too near a pole
// or spanning too much latitude for one local frame (InputError at /height/image or /height/texel_size).
FieldSize probe_image_field_size(const Job& job);

// The height image's texel sides (x, y) in world units when its file has a geotransform (what texel_size
// defaults to): a projected raster's pixel size twice, a geographic raster's pixel in metres in the local
// frame at its centre (docs/gis.md "Geographic DEMs"); nullopt otherwise (InputError when the job's
// texel_size is "from_file" then).
std::optional<std::array<double, 2>> image_texel_size(const Job& job);

// Whether the height image is a raster in a geographic CRS (its Earth curvature's default).
bool image_geographic(const Job& job);

// The height image's chosen channel as a field (heights as stored: scale and offset are applied by the
// caller), with nodata handling: NaN/Inf texels (and texels equal to height.nodata_value or to the file's
// NoData value) are an error naming the count and the first texel, unless height.nodata is "fill".
// Georeferenced rasters are read through GDAL (io/georaster_input.hpp); `georeference` receives their
// CRS and geotransform, and the holes that were filled (for every input); `source` the reader, format and
// sample type. Integer samples are the stored integers through either reader. The chosen channel is decoded
// straight into the field's heights, a band of rows at a time, with `progress` (the fraction read) after
// each.
HeightField load_image_field(const Job& job, double texel_size, Wrap wrap, Georeference& georeference,
                             HeightSource& source, const std::function<void(double)>& progress = {});

// The height band of a job whose heights are a georeferenced raster read through GDAL: the file, the band
// (height.channel), its NoData value, the whole raster's georeference (CRS, geotransform, the field's
// centre) and the reader, format and sample type. nullopt for an image OpenImageIO reads or a procedural
// field. InputError at /height/channel for a band the raster lacks.
struct GeoHeightBand {
  std::filesystem::path file;
  int band = 0;
  int width = 0, height = 0;
  std::optional<double> nodata;
  Georeference georeference;
  HeightSource source;
  // A PNG (placed by a world file): its values and channels are OpenImageIO's, as without the world file
  // (docs/heights.md); `band` is the channel's index, and GDAL only places it.
  bool image_values = false;
};
std::optional<GeoHeightBand> georaster_height_band(const Job& job);

// The nodata rule of a height field from `source` (an image's name as the job gives it, or "heights" for
// an array handed in by the Python module): NaN/Inf texels, texels equal to height.nodata_value or to
// `file_nodata` are an InputError at /height/image naming the count and the first texel, unless
// height.nodata is "fill": then they are filled (field/nodata.hpp) and marked in georeference.holes.
// Returns, when it fills them, a warning for holes that look like real heights (nodata_inside_heights);
// else "".
std::string apply_height_nodata(const Job& job, const std::string& source, HeightField& field,
                                Georeference& georeference, std::optional<double> file_nodata = std::nullopt);

// A warning when the texels equal to `value` (a NoData value) look like real heights: at least 8 of them,
// `value` strictly between the least and the greatest other finite height, and 90 % of them beside a
// texel of another height (thin lines and specks, as a contour of an integer DEM makes, not the blocks a
// void or a masked lake makes); else "".
std::string nodata_inside_heights(const HeightField& field, float value);

// Fills `texels` (already sized to the field) from the surface key at `pointer` ("/surface/albedo" or
// "/surface/emission"): a number, [r, g, b], or {"image", "colorspace", "scale"} of the field's size.
void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field,
                      std::vector<Rgb>& texels);
// The same into a SurfaceMap: a number or [r, g, b] is held once, an image per texel.
void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field, SurfaceMap& map);

// The job's environment (absent: uniform radiance 1) and the lights that belong to it (the built-in
// sky's sun) into scene.environment and scene.lights.
void load_lighting(const Job& job, Scene& scene);

}  // namespace hfbake
