#include "cli/scene_loader.hpp"

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <map>
#include <new>
#include <optional>

#include "cli/scene_inputs.hpp"
#include "cli/texture_plan.hpp"
#include "core/error.hpp"
#include "core/threads.hpp"
#include "field/procedural.hpp"
#include "io/crs_geodesy.hpp"
#include "io/exr_output.hpp"
#include "io/geotiff_output.hpp"
#include "io/load_environment.hpp"
#include "io/preview.hpp"
#include "methods/method_table.hpp"
#include "reference/bake_reference.hpp"
#include "reference/embree_field.hpp"
#include "terrain/earth.hpp"

namespace hfbake {

namespace {

Rgb rgb_of(const nlohmann::json& v) {
  if (v.is_number()) {
    const float x = v.get<float>();
    return {x, x, x};
  }
  return {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
}

ProceduralSpec procedural_spec(const nlohmann::json& p) {
  ProceduralSpec s;
  parse_procedural_kind(p["kind"].get<std::string>(), s.kind);  // the schema guarantees a known kind
  if (p.contains("size")) {
    s.width = p["size"][0].get<int>();
    s.height = p["size"][1].get<int>();
  }
  s.seed = p.value("seed", std::uint64_t(1));
  s.amplitude = p.value("amplitude", 0.0);
  s.feature_size = p.value("feature_size", 0.0);
  s.angle_deg = p.value("angle_deg", std::nan(""));  // NaN: the kind's default
  s.aspect_deg = p.value("aspect_deg", 0.0);
  s.radius = p.value("radius", 0.0);
  s.depth = p.value("depth", 0.0);
  s.step = p.value("step", 0.0);
  return s;
}

}  // namespace

SceneNeeds scene_needs(const Job& job) {
  SceneNeeds needs;
  needs.normals = needs.albedo = job.has_reference;  // the reference shades with both
  for (const BakeEntry& e : job.bakes) {
    const MethodInfo* m = find_method(e.method);
    needs.normals = needs.normals || !m || m->reads_normals;
    needs.albedo = needs.albedo || !m || m->reads_albedo;
  }
  return needs;
}

FieldSize probe_field_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (h.contains("procedural")) {
    const ProceduralSpec s = procedural_spec(h["procedural"]);
    return {s.width, s.height};
  }
  const FieldSize size = probe_image_field_size(job);
  // The sides every method supports (the procedural schema's limit): the sweeps' line indices (up to
  // width + height lines of up to 2^20 samples each, in int) and the reference's Embree grids. Checked on
  // the header, before the memory estimate or anything is allocated.
  if (size.width > kMaxFieldSide || size.height > kMaxFieldSide)
    throw InputError(job.file.string(), "/height/image",
                     h["image"].get<std::string>() + ": is " + std::to_string(size.width) + "x" +
                         std::to_string(size.height) + " texels; fields of up to " +
                         std::to_string(kMaxFieldSide) + " texels a side are supported");
  return size;
}

std::array<double, 2> job_texel_sides(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (h.contains("image"))
    if (const std::optional<std::array<double, 2>> from_file = image_texel_size(job)) {
      // Sides equal to 1e-9 (a geographic raster sized square, its local frame's rounding) are square: no
      // texel position across the largest field moves by 1e-4 texels.
      const auto [a, b] = *from_file;
      if (std::fabs(a - b) <= 1e-9 * std::max(a, b)) return {a, a};
      return *from_file;
    }
  if (h.contains("texel_size") && h["texel_size"].is_string())
    throw InputError(job.file.string(), "/height/texel_size",
                     "is \"from_file\" but the field is procedural: give texel_size as a number");
  const double t = h.value("texel_size", 1.0);
  return {t, t};
}

double job_texel_size(const Job& job) {
  return job_texel_sides(job)[0];
}

CurvatureOption job_curvature(const Job& job, bool geographic) {
  const nlohmann::json& h = job.doc["height"];
  CurvatureOption o;
  o.on = h.value("curvature", geographic);
  o.refraction = h.value("refraction", kDefaultRefraction);
  if (o.on && h.value("wrap", "clamp") == "repeat")
    throw InputError(job.file.string(), h.contains("curvature") ? "/height/curvature" : "/height/wrap",
                     "a repeating field has no place on the Earth: Earth curvature applies to clamp fields "
                     "only");
  if (h.contains("refraction") && !o.on)
    throw InputError(job.file.string(), "/height/refraction",
                     std::string("applies with Earth curvature only, which is off for this field (") +
                         (h.contains("curvature") ? "\"curvature\": false" : "a projected or local field") +
                         "): set \"curvature\": true or leave refraction out");
  return o;
}

double curvature_coefficient(const CurvatureOption& option, const Georeference& georeference) {
  if (!option.on) return 0;
  Ellipsoid ellipsoid;  // a sphere of the mean radius when the CRS names no ellipsoid
  double metres_per_unit = 1;
  if (const std::optional<CrsEarth> earth = crs_earth(georeference.crs_wkt)) {
    ellipsoid = {earth->semi_major, earth->semi_minor};
    metres_per_unit = earth->metres_per_unit;
  }
  const double lat = georeference.has_site ? georeference.site_latitude * kPi / 180 : 0.0;
  // c per world unit: the radii in the CRS's linear unit (the heights' unit, docs/gis.md).
  return EarthCurvature::at(ellipsoid, lat, option.refraction).mean_coefficient() * metres_per_unit;
}

int job_bounces(const Job& job) {
  return job.doc.value("bounces", 1);
}

namespace {

// Whether a bake of the job reads or writes through GDAL: heights from a georeferenced raster, GeoTIFF
// outputs.
bool uses_gdal(const Job& job, const FieldSize& size) {
  return job.output.geotiff || size.georaster;
}

// Whether a bake of the job loads the image module (io/oiio_codec.hpp) before its first method runs: an
// input file OpenImageIO reads (heights that are not a georeferenced raster, an albedo or emission image, an
// environment map).
bool reads_images(const Job& job, const FieldSize& size) {
  if (size.image_values) return true;
  for (const auto& [pointer, file] : job_input_files(job.doc))
    if (pointer != "/height/image" || !size.georaster) return true;
  return false;
}

// Whether output.previews writes any PNG: some entry writes a layer the previews show (io/preview.hpp
// is_previewed), or the job has a reference (its report's page shows images). An entry not resolved yet
// counts as one that does. A tiled bake writes no previews.
bool writes_previews(const Job& job, const FieldSize& size) {
  if (!job.output.previews || size.tile) return false;
  if (job.has_reference) return true;
  for (const BakeEntry& e : job.bakes) {
    if (!e.config) return true;
    for (const std::string& l : e.config->layers)
      if (is_previewed(l, layer_channel_count(l, e.config->directions))) return true;
  }
  return false;
}

// Whether it loads it to write a method's results: a PNG preview or an engine texture, written once the
// method has run (its working memory freed). A reference alone loads it after its tracing, for
// report.html's images.
bool writes_images(const Job& job, const FieldSize& size) {
  if (writes_previews(job, size)) return true;
  const nlohmann::json& output = job.doc.contains("output") ? job.doc["output"] : nlohmann::json::object();
  return output.contains("textures") && !output["textures"].empty();
}

// The process before its first method has written anything (kProcessBytes, kGdalProcessBytes or
// kImageProcessBytes, by the libraries loaded by then).
double process_before_writing(const Job& job, const FieldSize& size) {
  return reads_images(job, size) ? kImageProcessBytes
         : uses_gdal(job, size)  ? kGdalProcessBytes
                                 : kProcessBytes;
}

}  // namespace

std::size_t estimate_process_bytes(const Job& job, FieldSize size) {
  return std::size_t(writes_images(job, size) ? kImageProcessBytes : process_before_writing(job, size));
}

std::size_t estimate_peak_bytes(const Job& job, FieldSize size, std::vector<MemoryPart>* parts) {
  const double texels = double(size.width) * double(size.height);
  // The process before any field, while the first method runs; the image module's libraries come in (lift)
  // when that method's previews or textures are written, and stay for the methods after it and a reference;
  // a reference's report adds them after the tracing when nothing loaded them before (below).
  const double process = process_before_writing(job, size);
  const double lift = double(estimate_process_bytes(job, size)) - process;
  // The scene: heights (decoded straight into the field), the normals only when read (scene_needs), the
  // surface maps the job names.
  const SceneNeeds needs = scene_needs(job);
  const nlohmann::json surface = job.doc.value("surface", nlohmann::json::object());
  double scene_per_texel = 4;
  if (needs.normals) scene_per_texel += 12;
  // An albedo image is held per texel (read even when no method reads it: validate checks it); a number
  // or [r, g, b] is held once.
  if (surface.contains("albedo") && surface["albedo"].is_object()) scene_per_texel += 12;
  if (surface.contains("emission")) scene_per_texel += 12;
  // Writing a result whose widest layer has `widest` channels: a preview's RGB floats and bytes (15 bytes a
  // pixel, at most io/preview.hpp's 2048 px a side), or a layer's COG (geotiff_writing_bytes: GDAL reads the
  // layer itself; where the job fills holes, "nodata": "fill", the only way a result has any, the writer
  // copies it). A tile of a tiled bake writes a band's plane at a time into its work files.
  const double previews = writes_previews(job, size) ? 15 * std::min(texels, 2048.0 * 2048.0) : 0;
  const bool holes = job.doc["height"].value("nodata", "error") == "fill";
  auto writing = [&](int widest) {
    const double geotiff = !job.output.geotiff ? 0
                           : size.tile         ? 4.0 * texels
                                       : geotiff_writing_bytes(size.width, size.height, widest, holes);
    return std::max(previews, geotiff);
  };

  // Engine textures (io/texture_output.hpp), written one at a time after their stem's EXR: a texture's values
  // (two bytes a channel, an 8-bit one's also copied to bytes; an EXR texture's floats and OpenImageIO's
  // half copy of them). The height's textures (its normal) are written while the scene loads, from the
  // normal layer they read (12 bytes a texel), and bring the image libraries in before the first method.
  // A job not resolved yet (plan_textures needs its layers) counts none.
  std::map<std::string, double> texture_writing;  // by stem, the largest texture's bytes
  std::vector<PlannedTexture> textures;
  try {
    if (!size.tile) textures = plan_textures(job);
  } catch (const InputError&) {
  }
  for (const PlannedTexture& t : textures) {
    const double c = double(t.spec.channels.size());
    const bool exr = t.file.size() > 4 && t.file.compare(t.file.size() - 4, 4, ".exr") == 0;
    // The texture's own texels: the field's and its padding on every side (none on a repeat field).
    const double p = double(std::max(0, t.spec.padding));
    const double own = (double(size.width) + 2 * p) * (double(size.height) + 2 * p);
    const double bytes = own * c *
                             (exr                ? 6.0
                              : t.spec.bits == 8 ? 3.0
                                                 : 2.0) +
                         (t.stem == kHeightStem ? 12.0 * texels : 0.0);
    double& largest = texture_writing[t.stem];
    largest = std::max(largest, bytes);
  }
  const double height_textures = texture_writing[kHeightStem];

  MethodContext context;
  context.field.width = size.width;
  context.field.height = size.height;
  context.field.wrap =
      job.doc["height"].value("wrap", std::string("clamp")) == "repeat" ? Wrap::repeat : Wrap::clamp;
  context.bounces = job_bounces(job);
  context.uniform_environment = job_environment_uniform(job.doc);
  EnvironmentLoadOptions env_options;
  env_options.job_file = job.file.string();
  const EnvironmentBytes env =
      environment_bytes(job.doc.value("environment", nlohmann::json::object()), job.base_dir, env_options);
  context.environment_bytes = env.world;
  // Methods run one at a time; each one's layers are kept until the report when there is a reference.
  double kept = 0, peak = 0;
  // The reference adds the layers it traces after its paths (the layer table's LayerTrace): horizon and
  // horizon_distance for the first entry's K that bakes one, sh_visibility, and the first relief entry's
  // layers, whose horizons (up and down, doubles) it holds while it computes them
  // (reference/relief_reference.cpp).
  int horizon_channels = 0;
  double added_per_texel = 0;
  bool sh_visibility_added = false, relief_added = false;
  for (const BakeEntry& e : job.bakes) {
    // The entry's config (read by resolve_job; here only for a job not resolved yet).
    const MethodConfig r =
        e.config ? *e.config : resolve_method(e.params, context, job.file.string(), e.pointer);
    const MethodInfo* m = r.method;
    int channels = 0, widest = 0;
    std::size_t half_channels = 0, float_channels = 0;
    for (const std::string& l : r.layers) {
      const int n = layer_channel_count(l, r.directions);
      channels += n;
      widest = std::max(widest, n);
      const LayerKind* kind = find_layer_kind(l);
      (job.output.float_pixels || (kind && kind->float_storage) ? float_channels : half_channels) +=
          std::size_t(n);
    }
    const double layers = 4.0 * channels * texels;
    const double working = m->working_bytes ? m->working_bytes(r, context) : 0.0;
    // Its EXR: the half band it converts and OpenEXR's chunk buffers (io/exr_output.hpp).
    ExrOptions exr;
    exr.compression =
        job.output.compression.empty() ? default_exr_compression(r.layers) : job.output.compression;
    exr.tile_size = std::max(size.width, size.height) > kLargestScanlineExr ? 256 : 0;
    exr.threads = worker_threads();
    // A tile writes work GeoTIFFs instead, a band of its plane at a time (counted as half a band of rows).
    const double exr_band =
        size.tile ? 2.0 * channels * std::min(texels, 256.0 * size.width)
                  : exr_writing_bytes(size.width, size.height, half_channels, float_channels, exr);
    const double writes = std::max({writing(widest), exr_band, texture_writing[e.stem]});
    // The libraries, once loaded: by the entry before, or by the height's textures.
    const double before = &e == &job.bakes.front() && height_textures == 0 ? 0.0 : lift;
    peak = std::max(peak, kept + layers + std::max(before + working, lift + writes));
    if (job.has_reference) kept += layers;
    // The entry's own part, without the image libraries (their own part below).
    if (parts)
      parts->push_back({e.stem, std::size_t(layers + std::max(working, writes)), m->memory_knob, true});
    auto traced = [&](const std::string& l, LayerTrace t) {
      const LayerKind* k = find_layer_kind(l);
      return k && k->trace == t;
    };
    for (const std::string& l : r.layers)
      if (traced(l, LayerTrace::horizons) && horizon_channels == 0)
        horizon_channels = 2 * layer_channel_count(l, r.directions);
    for (const std::string& l : r.layers)
      if (traced(l, LayerTrace::sh_visibility) && !sh_visibility_added) {
        added_per_texel += 4.0 * layer_channel_count(l, r.directions);
        sh_visibility_added = true;
      }
    if (!relief_added && std::any_of(r.layers.begin(), r.layers.end(),
                                     [&](const std::string& l) { return traced(l, LayerTrace::relief); })) {
      for (const std::string& l : r.layers) added_per_texel += 4.0 * layer_channel_count(l, r.directions);
      added_per_texel += 16.0 * r.directions;
      relief_added = true;
    }
  }
  double reference = 0;
  if (job.has_reference) {
    // Its layers (value and standard error, 8 bytes a texel and channel) and Embree's geometry and BVH of
    // the triangulated field (reference/embree_field.hpp: 36 to 212 bytes a texel by reference.geometry,
    // and up to 16 MiB that do not grow with the field).
    int channels = 0;
    if (job.reference_options)
      for (const std::string& l : job.reference_options->layers) channels += layer_channel_count(l, 0);
    if (channels == 0) channels = 5;  // not resolved yet: ao, vsky, direct
    const reference::GeometryKind geometry =
        job.reference_options ? job.reference_options->geometry : reference::GeometryKind::quads;
    const double layers = (8.0 * channels + 4.0 * horizon_channels + added_per_texel) * texels;
    reference = layers + reference::embree_bytes_per_texel(geometry) * texels +
                reference::embree_fixed_bytes(geometry);
    // Its widest layer: direct (3 channels) or the horizons it traces; then report.html's images, after the
    // tracing (Embree's scene freed): beside the layers, a float copy of one layer's magnitudes (its
    // percentile; 3 channels at most) and the error map (report/report_html.cpp), and OpenImageIO's libraries
    // when nothing loaded them before. Its part is the larger.
    // The scores (report/compare.cpp) hold a layer's differences at a time, 4 bytes a value, then a horizon
    // layer's angles in degrees, 8 bytes a value: K channels' 8 K bytes a texel.
    const double scores = std::max(16.0, 4.0 * horizon_channels);
    const double report_page = layers + scores * texels + std::max(0.0, kImageProcessBytes - process - lift);
    const double written = std::max(writing(std::max(3, horizon_channels / 2)), texture_writing["reference"]);
    if (job.bakes.empty())
      // A reference alone: its previews or textures bring the image libraries in after the tracing, Embree's
      // scene freed, and its report.html, scored against nothing, shows no images.
      reference = std::max(reference, lift + layers + written);
    else
      reference = lift + std::max(reference + written, report_page);
    peak = std::max(peak, kept + reference);
  }
  // The environment's images are read and resampled before any method runs, when nothing of the bake is
  // held yet but the field; the world lat-long is kept through the bake (with the reference's sampling
  // tables when a reference traces).
  const double field_bytes = process + scene_per_texel * texels;
  const double scene = field_bytes + env.world + (job.has_reference ? env.tables : 0.0);
  const double total = std::max({scene + peak, field_bytes + env.loading, scene + lift + height_textures});
  if (parts) {
    // A smaller field shrinks the scene only where the field is most of it (not the process's fixed part).
    const double field_part = scene - process;
    // The image module an input image brings in (an image's heights, an albedo, an environment map), read
    // before the bake: a part of its own, as when it comes to write previews or textures.
    const double reader = process - (uses_gdal(job, size) ? kGdalProcessBytes : kProcessBytes);
    parts->insert(parts->begin(),
                  {"scene", std::size_t(scene - reader), field_part > process ? "a smaller field" : ""});
    if (reader > 0) parts->insert(parts->begin() + 1, {"image reader", std::size_t(reader), ""});
    if (lift > 0)
      parts->insert(parts->begin() + (reader > 0 ? 2 : 1),
                    {std::string(kImageLibrariesPart), std::size_t(lift),
                     "no previews or textures (OpenImageIO's libraries load to write them)"});
    if (env.loading > 0)
      parts->push_back({"environment", std::size_t(env.loading),
                        "a smaller environment image (24 bytes a pixel while it is read)"});
    if (job.has_reference)
      parts->push_back({"reference", std::size_t(reference - lift),
                        "fewer reference.layers (8 bytes a texel a channel; the sample count does not change "
                        "it) or bounces"});
  }
  return std::size_t(total);
}

namespace {

// A number in at most 6 significant digits, as a person reads it: 2, 0.5, 1e-06.
std::string short_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

std::optional<double> metres_per(std::string unit) {
  for (char& c : unit) c = char(std::tolower(static_cast<unsigned char>(c)));
  for (const char* m : {"m", "metre", "meter", "metres", "meters"})
    if (unit == m) return 1.0;
  for (const auto& [name, metres] : {std::pair<const char*, double>{"mm", 1e-3},
                                     {"millimetre", 1e-3},
                                     {"millimeter", 1e-3},
                                     {"millimetres", 1e-3},
                                     {"millimeters", 1e-3},
                                     {"cm", 1e-2},
                                     {"centimetre", 1e-2},
                                     {"centimeter", 1e-2},
                                     {"centimetres", 1e-2},
                                     {"centimeters", 1e-2},
                                     {"dm", 0.1},
                                     {"decimetre", 0.1},
                                     {"decimeter", 0.1},
                                     {"km", 1e3},
                                     {"kilometre", 1e3},
                                     {"kilometer", 1e3},
                                     {"kilometres", 1e3},
                                     {"kilometers", 1e3}})
    if (unit == name) return metres;
  for (const char* f : {"ft", "foot", "feet", "international foot", "foot (international)"})
    if (unit == f) return 0.3048;
  for (const char* f : {"us survey foot", "us-ft", "ftus", "foot_us", "us survey feet", "foot (us survey)"})
    if (unit == f) return 1200.0 / 3937.0;
  return std::nullopt;
}

double height_unit_ratio(const std::string& height_unit, double pixel_unit_metres) {
  const std::optional<double> metres = metres_per(height_unit);
  const double r = metres && pixel_unit_metres > 0 ? *metres / pixel_unit_metres : 1.0;
  return std::fabs(r - 1) > 1e-4 ? r : 1.0;
}

std::string unitless_heights_note(const std::string& pixel_unit, double pixel_unit_metres,
                                  const std::string& height_unit) {
  if (pixel_unit.empty() || pixel_unit_metres == 1.0 || !height_unit.empty()) return "";
  return "the band declares no unit: heights taken in " + pixel_unit +
         "; heights in metres need height_scale " + short_num(1 / pixel_unit_metres);
}

namespace {

// Every s-th of the field's heights that keep(z) accepts, s such that at most 2^20 texels are looked at:
// what the heights warnings take their percentiles from.
template <class Keep>
std::vector<float> sampled_heights(const HeightField& f, const Keep& keep) {
  const std::size_t n = f.z.size(), s = (n + (std::size_t(1) << 20) - 1) >> 20;
  std::vector<float> sample;
  sample.reserve(n / s + 1);
  for (std::size_t t = 0; t < n; t += s)
    if (keep(f.z[t])) sample.push_back(f.z[t]);
  return sample;
}

// The value of rank `rank` (0: the least) of `v`, reordering it.
double value_of_rank(std::vector<float>& v, std::size_t rank) {
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(rank), v.end());
  return double(v[rank]);
}

// Where most of a field's heights lie: the 1st and 99th percentiles (of every texel up to 2^20 of them, of
// every s-th beyond), and the texels standing out of that band by more than `apart` world units: how many,
// the farthest (i, j) and how far.
struct HeightBand {
  double lo = 0, hi = 0;
  std::size_t outliers = 0;
  int i = 0, j = 0;
  double farthest = 0;
};

HeightBand height_band(const HeightField& f, double apart) {
  std::vector<float> sample = sampled_heights(f, [](float) { return true; });
  const std::size_t m = sample.size();
  HeightBand b;
  b.lo = value_of_rank(sample, (m - 1) / 100);
  b.hi = value_of_rank(sample, m - 1 - (m - 1) / 100);
  for (std::size_t t = 0; t < f.z.size(); ++t) {
    const double z = f.z[t], off = z > b.hi ? z - b.hi : z < b.lo ? b.lo - z : 0.0;
    if (off <= apart) continue;
    ++b.outliers;
    if (off > b.farthest)
      b.farthest = off, b.i = int(t % std::size_t(f.width)), b.j = int(t / std::size_t(f.width));
  }
  return b;
}

// A georeferenced raster's texels stored as exactly 0 (world height `zero`) where one reaches a corner of
// the field: how many, that corner, and how far the 1st percentile of the other heights (sampled as
// height_band's) lies above them. The fill a reprojection leaves outside its source (gdalwarp without
// -dstnodata) looks so; count 0 when no corner is such a texel.
struct ZeroFill {
  std::size_t count = 0;
  int i = 0, j = 0;
  double below = 0;
};

ZeroFill zero_fill(const HeightField& f, float zero) {
  ZeroFill z;
  const int corners[4][2] = {{0, 0}, {f.width - 1, 0}, {0, f.height - 1}, {f.width - 1, f.height - 1}};
  const auto corner = std::find_if(std::begin(corners), std::end(corners),
                                   [&](const int* c) { return f.z[f.index(c[0], c[1])] == zero; });
  if (corner == std::end(corners)) return z;
  std::vector<float> rest = sampled_heights(f, [&](float v) { return v != zero; });
  if (rest.empty()) return {};
  z.count = std::size_t(std::count(f.z.begin(), f.z.end(), zero));
  z.i = (*corner)[0], z.j = (*corner)[1];
  z.below = value_of_rank(rest, (rest.size() - 1) / 100) - double(zero);
  return z;
}

}  // namespace

std::string heights_warning(const Scene& scene) {
  const HeightSource& s = scene.height_source;
  const HeightField& f = scene.field;
  const double texel = f.texel_size;
  const double relief = s.world_max - s.world_min;
  std::string warning;
  bool scale_named = false;  // the relief clause named the file's scale
  const double extent = std::max(f.width, f.height) * texel;
  const std::string scale_hint =
      s.integer ? "height_scale (world units per stored integer: a 16-bit image meant as 0..1 of a height H "
                  "needs H / 65535, an 8-bit one H / 255)"
                : "height_scale (world units per stored unit)";
  // A band that declares its heights in another unit than its pixels' (metres on a CRS in feet): every
  // slope would be off by their ratio unless height_scale converts them.
  const double unit_ratio = height_unit_ratio(s.height_unit, s.pixel_unit_metres);
  if (s.scale == 1 && unit_ratio != 1) {
    warning = "the band's heights are in " + s.height_unit + " and its pixels in " +
              (s.pixel_unit.empty() ? std::string("metres") : s.pixel_unit) + ": slopes come out " +
              short_num(unit_ratio > 1 ? unit_ratio : 1 / unit_ratio) + " times too " +
              (unit_ratio > 1 ? "flat" : "steep") + "; give height_scale " + short_num(unit_ratio) +
              " (docs/gis.md)";
  } else if (relief == 0) {
    warning = "the field is flat (every height is " + short_num(s.world_min) +
              "): every method bakes it unoccluded";
  } else if (relief < 0.01 * extent && scene.georeference.crs_wkt.empty()) {
    // A raster with a CRS holds elevations in its units: a plain's lidar tile of a few metres' relief is a
    // common relief bake (docs/heights.md), not a map missing its height_scale.
    warning = "the relief (" + short_num(relief) + " world units) is " + short_num(100 * relief / extent) +
              " % of the field's " + short_num(extent) +
              "-unit side: nearly flat, the bake will be close to unoccluded; if the heights are meant "
              "higher, set " +
              scale_hint;
  } else if (const ZeroFill fill = f.z.size() == f.texel_count() && !scene.georeference.crs_wkt.empty()
                                       ? zero_fill(f, float(s.offset))
                                       : ZeroFill{};
             fill.count > 0 && fill.below > 0.01 * extent) {
    // Sea level lies next to low ground (a beach), so a coast is no such fill.
    char share[32];
    std::snprintf(share, sizeof share, "%.3g", 100.0 * double(fill.count) / double(f.texel_count()));
    warning = std::to_string(fill.count) + " texels (" + share + " %) are stored as exactly 0, the corner (" +
              std::to_string(fill.i) + ", " + std::to_string(fill.j) + ") among them, " +
              short_num(fill.below) +
              " world units or more below 99 % of the other heights: the fill a reprojection leaves outside "
              "its source (gdalwarp without -dstnodata)? Baked as they are, they are ground that far down; "
              "declare them NoData (\"nodata_value\": 0 with \"nodata\": \"fill\" in height, or gdalwarp "
              "-dstnodata -9999) (docs/gis.md)";
  } else if (const HeightBand band =
                 f.z.size() == f.texel_count() && scene.georeference.crs_wkt.empty() && s.reader != "numpy"
                     ? height_band(f, 0.005 * extent)
                     : HeightBand{};
             band.outliers > 0 && band.hi - band.lo < 0.01 * extent) {
    // A nearly flat map whose range a few texels set (a marker, a hot pixel, a white border): its relief
    // looks plausible, yet the bake is close to unoccluded away from them. Not for the Python module's
    // arrays, which carry no CRS: a DEM read by read_dem (a plain with a few buildings) is no image.
    warning = "98 % of the heights lie within " + short_num(band.hi - band.lo) + " world units (" +
              short_num(100 * (band.hi - band.lo) / extent) + " % of the field's " + short_num(extent) +
              "-unit side: nearly flat), but " + std::to_string(band.outliers) +
              (band.outliers == 1 ? " texel stands" : " texels stand") + " out of them by up to " +
              short_num(band.farthest) + " (the farthest at texel (" + std::to_string(band.i) + ", " +
              std::to_string(band.j) + ")) and set the relief of " + short_num(relief) +
              ": away from them the bake will be close to unoccluded; if they are markers, a border or "
              "noise, remove them from the image; if the heights are meant higher, set " +
              scale_hint;
  } else if (relief > 4 * extent) {
    warning = "the relief (" + short_num(relief) + " world units) is " + short_num(relief / extent) +
              " times the field's " + short_num(extent) + "-unit side: steeper than any terrain; check " +
              scale_hint + " and texel_size";
    // A raster that declares a scale of its own (an integer band of centimetres: scale 0.01) is read as
    // stored (docs/heights.md): the likeliest cause, named with the key that applies it.
    scale_named = s.file_scale != 1 && s.scale == 1;
    if (scale_named)
      warning += " (the file declares scale " + short_num(s.file_scale) +
                 ", not applied: \"height_scale\": " + short_num(s.file_scale) +
                 (s.file_offset != 0 ? " and \"height_offset\": " + short_num(s.file_offset) + " apply it)"
                                     : std::string(" applies it)"));
    // A value that marks missing data in common DEM formats, stored but declared nowhere: holes read as
    // heights (docs/gis.md, NoData).
    for (const double sentinel : {-9999.0, -32768.0, -32767.0, -99999.0, double(-FLT_MAX)})
      if (s.stored_min == sentinel) {
        warning += "; if the texels stored as " + short_num(sentinel) +
                   " mark missing data, \"nodata_value\": " + short_num(sentinel) +
                   " with \"nodata\": \"fill\" in height makes them holes";
        break;
      }
  } else if (const std::string w = site_scale_warning(scene.georeference.site_scale,
                                                      scene.georeference.crs_name, s.scale, unit_ratio);
             !w.empty()) {
    warning = w;
  } else if (s.format == "jpeg" || s.format == "JPEG") {
    warning =
        "JPEG is lossy: the heights carry its compression artefacts (a TIFF or PNG of the same "
        "heights keeps what was stored; docs/heights.md)";
  }
  // A declared scale or offset the job does not apply, whatever the relief (a band of decimetres reads ten
  // times too steep, short of the relief clause above): as `hfbake horizon` and read_dem warn.
  if ((s.file_scale != 1 || s.file_offset != 0) && s.scale == 1 && s.offset == 0 && !scale_named)
    warning += std::string(warning.empty() ? "" : "; and ") + "the file declares scale " +
               short_num(s.file_scale) + " and offset " + short_num(s.file_offset) +
               ", not applied (heights are the stored values, docs/heights.md): \"height_scale\": " +
               short_num(s.file_scale) + " and \"height_offset\": " + short_num(s.file_offset) +
               " apply them";
  if (!s.nodata_note.empty()) warning += (warning.empty() ? "" : "; and ") + s.nodata_note;
  return warning;
}

namespace {

// Whether the job's height_scale and height_offset are the file's declared scale and offset, in the pixels'
// unit where the band declares another (as hfbake init writes them).
bool declared_scale_applied(const HeightSource& s) {
  const double r = height_unit_ratio(s.height_unit, s.pixel_unit_metres);
  const auto same = [](double a, double b) { return std::fabs(a - b) <= 1e-9 * std::max(1.0, std::fabs(b)); };
  return same(s.scale, s.file_scale * r) && same(s.offset, s.file_offset * r);
}

}  // namespace

HeightsReport describe_heights(const Job& job, const Scene& scene) {
  const HeightSource& s = scene.height_source;
  const HeightField& f = scene.field;
  const double texel = f.texel_size;
  std::string line = "heights: ";
  const nlohmann::json& h = job.doc["height"];
  if (s.reader == "procedural") {
    line += "procedural " + s.format;
  } else {
    line += h["image"].get<std::string>() + " through " + s.reader + " (" + s.format + ", " +
            (s.channel.empty() ? "" : s.channel + ", ") + s.sample_type +
            (s.integer ? " integers as stored" : "") + ")";
    if (s.file_scale != 1 || s.file_offset != 0)
      line += " (the file declares scale " + short_num(s.file_scale) + " and offset " +
              short_num(s.file_offset) +
              (declared_scale_applied(s) ? ", as the job's height_scale and height_offset apply them)"
                                         : ", not applied: height_scale and height_offset apply them)");
  }
  line += "; " + std::to_string(f.width) + "x" + std::to_string(f.height) + " texels of " + short_num(texel);
  if (!f.square_texels()) line += " x " + short_num(f.dy());
  line += " (" + short_num(f.width * texel) + " x " + short_num(f.height * f.dy()) + " world units";
  if (!s.pixel_unit.empty() && s.pixel_unit_metres != 1.0) line += ", the CRS's " + s.pixel_unit;
  if (!f.square_texels())
    line +=
        ", a geographic raster in the local frame at latitude " + short_num(scene.georeference.site_latitude);
  line += ")";
  const bool transformed = s.scale != 1 || s.offset != 0;
  if (transformed) {
    line += "; stored " + short_num(s.stored_min) + " .. " + short_num(s.stored_max) + " x height_scale " +
            short_num(s.scale);
    if (s.offset != 0) line += " + height_offset " + short_num(s.offset);
    line += " ->";
  } else {
    line += ";";
  }
  const double relief = s.world_max - s.world_min;
  line += " heights " + short_num(s.world_min) + " .. " + short_num(s.world_max) + " world units (relief " +
          short_num(relief) + ")";
  if (s.scale == 1)
    if (const std::string note = unitless_heights_note(s.pixel_unit, s.pixel_unit_metres, s.height_unit);
        !note.empty())
      line += " (" + note + ")";
  // "nodata": "fill": how much of the field is filled (the outputs mark it NoData, docs/gis.md).
  const auto& holes = scene.georeference.holes;
  if (const std::size_t n = std::size_t(std::count(holes.begin(), holes.end(), std::uint8_t(1))); n > 0) {
    char share[32];
    std::snprintf(share, sizeof share, "%.2g", 100.0 * double(n) / double(f.texel_count()));
    line +=
        "; " + std::to_string(n) + " texels without a height (" + share + " %) filled from their neighbours";
  }

  if (scene.curvature > 0) {
    // c is per world unit: 1 km is 1000 / u world units of u metres, and the drop c (1000 / u)^2 of them
    // is c 1e6 / u metres.
    const double u = s.pixel_unit_metres > 0 ? s.pixel_unit_metres : 1.0;
    line += "; Earth curvature on (refraction " + short_num(scene.refraction) + ": a point 1 km away is " +
            short_num(scene.curvature * 1e6 / u) + " m lower, c = " + short_num(scene.curvature) +
            " per world unit)";
  } else {
    line += "; Earth curvature off (flat";
    line += scene.height_source.geographic ? "" : "; \"curvature\": true in height turns it on";
    line += ")";
  }

  HeightsReport report{line, heights_warning(scene)};
  if (!s.unread.empty())
    report.warning +=
        (report.warning.empty() ? "" : "; and ") + h["image"].get<std::string>() + ": " + s.unread;
  return report;
}

std::string site_scale_warning(double k, const std::string& crs_name, double scale, double unit_ratio) {
  // A conformal projection far from its true scale: its map metres are not ground metres, so every slope is
  // flattened by k, less what height_scale makes up beyond the unit.
  if (!far_from_true_scale(k)) return "";  // true to scale (or no CRS): whatever height_scale does
  const double left = k * unit_ratio / scale;
  if (!(std::fabs(left - 1) > 0.01)) return "";
  return "the CRS's map units are " + short_num(k) + " times the ground's at the field's centre (" +
         crs_name + "): slopes come out " + short_num(left >= 1 ? left : 1 / left) + " times too " +
         (left >= 1 ? "flat" : "steep") +
         "; warp the DEM to a CRS true to scale there (a UTM zone), or give height_scale " +
         short_num(k * unit_ratio) + " (docs/gis.md)";
}

Scene load_scene(const Job& job, const std::function<void(double)>& progress) {
  const nlohmann::json& h = job.doc["height"];
  const std::array<double, 2> sides = job_texel_sides(job);
  const double texel = sides[0];
  const Wrap wrap = h.value("wrap", "clamp") == "repeat" ? Wrap::repeat : Wrap::clamp;
  Georeference georeference;
  georeference.geotransform = local_geotransform(texel);
  HeightSource source;
  HeightField field;
  if (h.contains("procedural")) {
    field = make_procedural(procedural_spec(h["procedural"]), texel, wrap);
    source.reader = "procedural";
    source.format = h["procedural"]["kind"].get<std::string>();
  } else {
    try {
      field = load_image_field(job, texel, wrap, georeference, source, progress);
    } catch (const std::bad_alloc&) {
      // Under a --memory-limit above what the machine has, the estimate lets through a header that
      // declares more texels than can be held (a damaged header can declare any size).
      const FieldSize size = probe_field_size(job);
      throw InputError(
          job.file.string(), "/height/image",
          h["image"].get<std::string>() + ": its " + std::to_string(size.width) + "x" +
              std::to_string(size.height) +
              " texels do not fit in this machine's memory (the read could not allocate "
              "them): is --memory-limit above the memory there is, or the file's header damaged?");
    }
    if (sides[1] != sides[0]) field.texel_size_y = sides[1];
  }
  return complete_scene(job, std::move(field), std::move(georeference), std::move(source));
}

void to_world_heights(const Job& job, float* z, std::size_t n) {
  const nlohmann::json& h = job.doc["height"];
  const double scale = h.value("height_scale", 1.0), offset = h.value("height_offset", 0.0);
  if (scale != 1.0 || offset != 0.0)
    for (std::size_t t = 0; t < n; ++t) z[t] = float(z[t] * scale + offset);
}

Scene complete_scene(const Job& job, HeightField field, Georeference georeference, HeightSource read_by) {
  Scene scene;
  scene.name = job.name;
  scene.field = std::move(field);
  scene.georeference = std::move(georeference);
  scene.height_source = std::move(read_by);
  HeightSource& source = scene.height_source;
  const nlohmann::json& doc = job.doc;
  const nlohmann::json& h = doc["height"];
  const double scale = h.value("height_scale", 1.0), offset = h.value("height_offset", 0.0);
  source.scale = scale;
  source.offset = offset;
  if (!scene.field.z.empty()) {
    const auto [lo, hi] = std::minmax_element(scene.field.z.begin(), scene.field.z.end());
    source.stored_min = *lo;
    source.stored_max = *hi;
  }
  to_world_heights(job, scene.field.z.data(), scene.field.z.size());
  if (!scene.field.z.empty()) {
    const auto [lo, hi] = std::minmax_element(scene.field.z.begin(), scene.field.z.end());
    source.world_min = *lo;
    source.world_max = *hi;
  }
  if (scene.field.width < 2 || scene.field.height < 2) {
    const std::string size = std::to_string(scene.field.width) + "x" + std::to_string(scene.field.height);
    if (h.contains("image"))
      throw InputError(job.file.string(), "/height/image",
                       job.resolve(h["image"].get<std::string>()).string() + " is " + size +
                           " texels; at least 2x2 are needed");
    throw InputError(job.file.string(), "/height",
                     "the field is " + size + "; at least 2x2 texels are needed");
  }
  // Heights whose squares of differences overflow float would turn normals and slopes into inf and NaN
  // downstream: refuse them here (validate loads the scene too). 1e12 world units is far beyond any terrain.
  constexpr float kMaxHeight = 1e12f;
  for (std::size_t t = 0; t < scene.field.z.size(); ++t)
    if (!(std::fabs(scene.field.z[t]) <= kMaxHeight)) {
      const int i = int(t % std::size_t(scene.field.width)), j = int(t / std::size_t(scene.field.width));
      char value[32];
      std::snprintf(value, sizeof value, "%g", double(scene.field.z[t]));
      throw InputError(job.file.string(), "/height",
                       "texel (" + std::to_string(i) + ", " + std::to_string(j) + ") is " + value +
                           " world units high; heights (after height_scale and height_offset) must be within "
                           "+-1e12");
    }
  const SceneNeeds needs = scene_needs(job);
  if (needs.normals) scene.normals = compute_normals(scene.field);

  const std::size_t n = scene.field.texel_count();
  const nlohmann::json surface = doc.value("surface", nlohmann::json::object());
  if (surface.contains("albedo"))
    load_surface_map(job, "/surface/albedo", scene.field, scene.surface.albedo);
  else if (needs.albedo)
    scene.surface.albedo.assign(n, Rgb{0.5f, 0.5f, 0.5f});
  if (surface.contains("emission")) {
    scene.surface.emission.assign(n, Rgb{});
    load_surface_map(job, "/surface/emission", scene.field, scene.surface.emission);
  }

  load_lighting(job, scene);
  if (doc.contains("lights")) {
    for (const auto& l : doc["lights"]) {
      const auto& d = l["directional"];
      DirectionalLight light;
      light.direction = normalize({d["direction"][0].get<double>(), d["direction"][1].get<double>(),
                                   d["direction"][2].get<double>()});
      light.angular_diameter = d.value("angular_diameter_deg", 0.0) * kPi / 180.0;
      light.irradiance = rgb_of(d["irradiance"]);
      scene.lights.push_back(light);
    }
  }
  scene.bounces = job_bounces(job);
  const CurvatureOption curvature = job_curvature(job, source.geographic);
  scene.curvature = curvature_coefficient(curvature, scene.georeference);
  scene.refraction = curvature.refraction;
  return scene;
}

}  // namespace hfbake
