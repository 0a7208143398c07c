// Builds a job's Scene: the height field (image or procedural) with nodata handling, scale and normals,
// the surface maps, the environment and the lights. All file reading of a bake happens here.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "field/scene.hpp"
#include "job/manifest.hpp"

namespace hfbake {

struct FieldSize {
  int width = 0, height = 0;
  // A tile of a tiled bake (cli/tile_command.hpp): its layers go into work GeoTIFFs a band at a time, not
  // through a COG of their own.
  bool tile = false;
  // The heights are a georeferenced raster read through GDAL (probe_field_size says; a tile's always are).
  bool georaster = false;
  // ... whose values OpenImageIO reads (values_through_image_reader: a PNG with a world file).
  bool image_values = false;
};

// The longest side of a field (the procedural schema's maximum, and an image's): 2^20 texels.
inline constexpr int kMaxFieldSide = 1 << 20;

// The height field's size, from the procedural spec or the image header (no pixels are read); InputError
// at /height/image for an image with a side beyond kMaxFieldSide.
FieldSize probe_field_size(const Job& job);

// Bytes a bake of `job` needs at peak (field, normals, surface maps, the largest method's layers and
// scratch), estimated from the size alone so an absurd job is refused before anything is allocated.
// `parts` (optional): what the estimate is made of, for messages: "scene" (field, normals, surface maps),
// each bake entry's stem (its layers and working memory), "reference" (its layers). Methods run one at a
// time, so the peak is less than their sum when there is no reference.
// A part of estimate_peak_bytes: the scene, each bake entry (its layers and the most it holds beside them,
// working or writing), the environment while it is read, the reference. The entries run one at a time, so
// the largest of them counts, and the environment is read before any: the total is the scene plus the
// larger of the largest entry's and the environment's part, plus the reference's.
struct MemoryPart {
  std::string name;
  std::size_t bytes = 0;
  std::string knob;    // what shrinks it (MethodInfo::memory_knob for a method)
  bool entry = false;  // a bake entry's
};
std::size_t estimate_peak_bytes(const Job& job, FieldSize size, std::vector<MemoryPart>* parts = nullptr);
// The part of the image module's libraries, when a job loads them only to write previews or textures: after
// its first entry has run, whose working memory is freed by then, so not simply added to it.
inline constexpr const char* kImageLibrariesPart = "image libraries";
// The process itself, before any field: libraries and thread pools (measured: 45 MiB for a 16^2 bake);
// with GDAL's drivers and cache, when the job reads or writes through it (55 MiB reading a 64 x 48 PNG with
// a world file, 61 MiB reading a 16^2 GeoTIFF, 70 MiB also writing COGs: the constant is the middle one, the
// writing's own bytes are counted beside it); with OpenImageIO's libraries, when the job loads them (139 MiB
// with a PNG preview, 151 MiB reading a 20000 x 2 EXR).
inline constexpr double kProcessBytes = 48.0 * (1 << 20);
inline constexpr double kGdalProcessBytes = 64.0 * (1 << 20);
inline constexpr double kImageProcessBytes = 150.0 * (1 << 20);
// The process's own part of estimate_peak_bytes (kProcessBytes, kGdalProcessBytes or kImageProcessBytes, by
// the libraries the job loads before it bakes): held once by a process whatever number of jobs it bakes.
std::size_t estimate_process_bytes(const Job& job, FieldSize size);

// The job's texel sides (x, y): a georeferenced height raster's pixel size (the job's texel_size, when
// given, must agree with it; a geographic raster's pixel in metres in its local frame, docs/gis.md), else
// height.texel_size (default 1) twice. InputError for "from_file" without one. job_texel_size: the x side.
std::array<double, 2> job_texel_sides(const Job& job);
double job_texel_size(const Job& job);

// The job's Earth curvature (height.curvature, height.refraction), read once: on by default for a
// geographic raster, off otherwise; refraction k (default 0.13, Gauss's coefficient, docs/gis.md "Earth
// curvature") only with curvature on (InputError at /height/refraction otherwise).
struct CurvatureOption {
  bool on = false;
  double refraction = 0.13;
};
CurvatureOption job_curvature(const Job& job, bool geographic);
// The Scene's lowering coefficient c = (1 - k) / (2 R) per world unit (0: off): R = sqrt(M N) of the CRS's
// ellipsoid at the field's centre latitude (a sphere of the mean radius at the equator without a CRS or a
// site), in the CRS's linear unit.
double curvature_coefficient(const CurvatureOption& option, const Georeference& georeference);

// The job's "bounces" (default 1).
int job_bounces(const Job& job);

// What the job's methods and its reference read from the Scene besides the heights and the lighting
// (MethodInfo::reads_normals / reads_albedo): load_scene builds only that, the estimate counts only that.
struct SceneNeeds {
  bool normals = false;
  bool albedo = false;
};
SceneNeeds scene_needs(const Job& job);

// Metres in a unit of length as a raster band names it (GDAL's unit type; a CRS gives its own), case
// ignored: the metre and its millimetre, centimetre, decimetre and kilometre, the international foot and the
// US survey foot; nullopt for a name not known here. The Python module's read_dem asks it too.
std::optional<double> metres_per(std::string unit);
// The factor that takes heights in `height_unit` into pixels `pixel_unit_metres` metres long: 1 when the
// unit is not known (metres_per) or within 1e-4 of the pixels'.
double height_unit_ratio(const std::string& height_unit, double pixel_unit_metres);

// For a raster in a CRS whose unit is not the metre (`pixel_unit`, `pixel_unit_metres` metres each) and a
// band that declares no unit for its heights: they are taken in the CRS's unit, which a DEM in feet with
// heights in metres is not (docs/gis.md). The note says so and gives the height_scale for metres; empty for
// any other raster. The heights line carries it, and the Python module's read_dem warns with it.
std::string unitless_heights_note(const std::string& pixel_unit, double pixel_unit_metres,
                                  const std::string& height_unit);

// What validate and bake warn about a scene's heights (empty: nothing): heights in another unit than the
// pixels, or a relief implausible for the field's extent E (its longer side in world units): zero, under 1 %
// of E (the bake comes out nearly unoccluded: an integer image meant as 0..1, or a missing height_scale) or
// over 4 E (steeper than terrain: integers taken as metres that are not, or a wrong texel_size); else a CRS
// far from true scale, or a lossy JPEG. docs/heights.md states the rule; the Python module's array
// functions warn with it too (docs/python.md).
std::string heights_warning(const Scene& scene);

// What validate and bake say about the heights: `line` names the reader, the field's size, the texel size
// and the height range in world units; `warning`: heights_warning, and what of the height file was not read.
struct HeightsReport {
  std::string line;
  std::string warning;
};
HeightsReport describe_heights(const Job& job, const Scene& scene);
// The warning for a field whose CRS's map units are k times the ground's at its centre (Web Mercator away
// from the equator): slopes come out k times too flat. Empty when k is within 1 % of 1 (a CRS true to scale
// there, or none). `scale`: the job's height_scale, `unit_ratio` the factor of it that converts the heights'
// unit into the pixels' (heights_warning): what is left, k unit_ratio / scale, is the flattening warned
// about (none when the job gives the advised height_scale, k unit_ratio). `hfbake horizon` measures on the
// ground at its point instead (cli/horizon_command.cpp).
std::string site_scale_warning(double k, const std::string& crs_name, double scale = 1,
                               double unit_ratio = 1);
// Whether a CRS whose map units are k times the ground's is far from true scale: k more than 1 % off 1 (a
// UTM zone, 0.9996 to 1.001, is not). site_scale_warning warns of such a field; `hfbake horizon` measures
// on the ground at such a point.
inline bool far_from_true_scale(double k) {
  return std::fabs(k - 1) > 0.01;
}

// The job's Scene. Scene::normals and the constant albedo are filled only when scene_needs says a method
// reads them (an albedo map the job names is always read, so validate checks it). `progress` (optional): the
// fraction of the height image read so far, while it is read.
Scene load_scene(const Job& job, const std::function<void(double)>& progress = {});

// The rest of load_scene once the heights are read (as stored, nodata handled, `georeference` filled):
// height_scale and height_offset, the checks on the field's size and heights, the normals and surface maps
// scene_needs asks for, the lighting and the bounces. The Python module hands its arrays in here. `read_by`:
// the reader that gave the heights (Scene::height_source; its ranges are filled in here).
Scene complete_scene(const Job& job, HeightField field, Georeference georeference, HeightSource read_by = {});

// Stored heights in world units, in place: z * height_scale + height_offset, rounded to float. The one rule
// every height the job bakes goes through (complete_scene's field, a tiled bake's coarse copies).
void to_world_heights(const Job& job, float* z, std::size_t n);

}  // namespace hfbake
