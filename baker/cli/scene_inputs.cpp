#include "cli/scene_inputs.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include "core/error.hpp"
#include "field/nodata.hpp"
#include "io/crs_geodesy.hpp"
#include "io/georaster_input.hpp"
#include "io/image_input.hpp"
#include "io/load_environment.hpp"
#include "job/content_hash.hpp"
#include "terrain/earth.hpp"

namespace hfbake {

namespace {

InputSite site(const Job& job, const std::string& pointer) {
  return {job.file.string(), pointer};
}

// A number as a person writes it: 2, 0.5, 1e-06 (not std::to_string's 2.000000).
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::optional<float> nodata_value(const nlohmann::json& h) {
  if (!h.contains("nodata_value")) return std::nullopt;
  return h["nodata_value"].get<float>();
}

// A geographic raster's texel in metres in the local frame at its centre (terrain/earth.hpp
// GeographicFrame), after the checks that frame needs: a CRS with an ellipsoid, no row beyond
// kMaxFrameLatitude, an east-west scale error within kMaxFrameScaleError at the northern and southern rows.
std::array<double, 2> geographic_texel(const Job& job, const GeoRasterInfo& info, const std::string& file) {
  auto fail = [&](const std::string& what) {
    throw InputError(job.file.string(), "/height/image", file + what);
  };
  const std::optional<CrsEarth> earth = crs_earth(info.crs_wkt);
  if (!earth) fail(": has a geographic CRS (" + info.crs_name + ") without an ellipsoid GDAL can read");
  const Ellipsoid e{earth->semi_major, earth->semi_minor};
  const auto& g = info.geotransform;
  constexpr double kRad = kPi / 180;
  const double lat_a = g[3] + 0.5 * g[5], lat_b = g[3] + (info.height - 0.5) * g[5];
  const double lat0 = g[3] + 0.5 * info.height * g[5];
  if (!(std::max(std::abs(lat_a), std::abs(lat_b)) <= kMaxFrameLatitude))
    fail(": its rows reach latitude " + num(std::abs(lat_a) > std::abs(lat_b) ? lat_a : lat_b) +
         "; geographic DEMs are baked up to " + num(kMaxFrameLatitude) +
         " degrees: reproject it (e.g. gdalwarp -t_srs EPSG:3413)");
  const double error = std::max(std::abs(frame_scale_error(e, lat0 * kRad, lat_a * kRad)),
                                std::abs(frame_scale_error(e, lat0 * kRad, lat_b * kRad)));
  if (!(error <= kMaxFrameScaleError))
    fail(": spans latitudes " + num(std::min(lat_a, lat_b)) + " to " + num(std::max(lat_a, lat_b)) +
         ", too far for one local frame (its east-west scale is " + num(100 * error) +
         " % off at the edge rows, at most " + num(100 * kMaxFrameScaleError) +
         " % is baked): crop it (gdal_translate -projwin) or reproject it (gdalwarp -t_srs)");
  const GeographicFrame frame = GeographicFrame::at(e, lat0 * kRad);
  return {std::abs(g[1]) * frame.east_per_degree, std::abs(g[5]) * frame.north_per_degree};
}

// The height image's header through GDAL when it is a georeferenced raster (nullopt: an image for
// OpenImageIO), after every check bake and validate make of its georeferencing: a rotated or sheared
// geotransform, non-square pixels of a projected CRS, a job texel_size that disagrees with the pixel size
// (or any job texel_size for a geographic CRS, whose texels are the local frame's, in metres), a
// geographic raster the local frame does not hold (geographic_texel).
std::optional<GeoRasterInfo> checked_georaster(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  const std::string image = h["image"].get<std::string>();
  std::optional<GeoRasterInfo> info = probe_georaster(job.resolve(image));
  if (!info) return info;
  auto fail = [&](const std::string& pointer, const std::string& what) {
    throw InputError(job.file.string(), pointer, what);
  };
  const std::string file = job.resolve(image).string();
  if (!info->placed_by.empty())
    fail("/height/image", file + ": is placed by " + info->placed_by +
                              ", not by a geotransform: warp it onto a north-up grid first (gdalwarp " +
                              image + " warped.tif)");
  if (!info->crs_wkt.empty() && !info->has_geotransform)
    fail("/height/image", file + ": has a CRS (" + info->crs_name +
                              ") but no geotransform, so its pixels have no size or place in it: give it one "
                              "(gdal_edit.py -a_ullr) or leave the CRS out (gdal_edit.py -a_srs \"\")");
  if (!info->has_geotransform) return info;
  const auto& g = info->geotransform;
  if (!north_up(g))
    fail("/height/image", file + ": is rotated or sheared (geotransform " + num(g[2]) + ", " + num(g[4]) +
                              "); warp it north-up first (gdalwarp)");
  if (const std::string problem = geographic_unit_problem(*info); !problem.empty())
    fail("/height/image", file + ": " + problem);
  if (info->geographic) {
    if (h.contains("texel_size") && h["texel_size"].is_number())
      fail("/height/texel_size", "is given, but " + image + " has a geographic CRS (" + info->crs_name +
                                     "), whose texels are measured on its ellipsoid: leave texel_size out");
    geographic_texel(job, *info, file);
    return info;
  }
  const double sx = std::abs(g[1]), sy = std::abs(g[5]);
  if (!(std::abs(sx - sy) <= 1e-9 * std::max(sx, sy)))
    fail("/height/image", file + ": has non-square pixels (" + num(sx) + " x " + num(sy) +
                              "); hfbake needs square texels: resample it first, e.g. gdalwarp -tr S S");
  // The file's pixel size becomes the texel size: the range job.schema.json gives texel_size.
  if (!(sx >= 1e-6 && sx <= 1e6))
    fail("/height/image", file + ": has a pixel size of " + num(sx) +
                              (info->linear_unit.empty() ? "" : " " + info->linear_unit) +
                              "; a texel size must lie in [1e-6, 1e6] (beyond, world positions lose float "
                              "precision): give the raster another geotransform (gdal_edit.py -tr)");
  if (h.contains("texel_size") && h["texel_size"].is_number()) {
    const double t = h["texel_size"].get<double>();
    if (!(std::abs(t - sx) <= 1e-9 * sx)) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "is %.9g but the pixel size of %s is %.9g", t, image.c_str(), sx);
      fail("/height/texel_size",
           std::string(buf) + (info->linear_unit.empty() ? "" : " " + info->linear_unit) +
               ": leave texel_size out (or set \"from_file\") to use the file's, or resample the file "
               "(gdalwarp -tr); height_scale converts the heights' unit");
    }
  }
  return info;
}

}  // namespace

std::vector<std::pair<std::string, std::filesystem::path>> job_read_files(const Job& job) {
  std::vector<std::pair<std::string, std::filesystem::path>> files;
  for (const auto& [pointer, rel] : job_input_files(job.doc))
    for (const std::filesystem::path& file : raster_files(job.resolve(rel)))
      files.emplace_back(pointer, file);
  return files;
}

std::string job_content_hash(const Job& job) {
  std::vector<std::filesystem::path> files;
  for (const auto& [pointer, file] : job_read_files(job)) files.push_back(file);
  return content_hash_of(job, files);
}

FieldSize probe_image_field_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (const std::optional<GeoRasterInfo> geo = checked_georaster(job))
    return {.width = geo->width,
            .height = geo->height,
            .georaster = true,
            .image_values = values_through_image_reader(*geo)};
  const ImageInfo info = probe_image(job.resolve(h["image"].get<std::string>()), site(job, "/height/image"));
  return {info.width, info.height};
}

std::optional<std::array<double, 2>> image_texel_size(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  const std::optional<GeoRasterInfo> geo = checked_georaster(job);
  if (geo && geo->geographic)
    return geographic_texel(job, *geo, job.resolve(h["image"].get<std::string>()).string());
  if (geo && geo->has_geotransform)
    return std::array<double, 2>{std::abs(geo->geotransform[1]), std::abs(geo->geotransform[1])};
  if (h.contains("texel_size") && h["texel_size"].is_string())
    throw InputError(job.file.string(), "/height/texel_size",
                     "is \"from_file\" but " + h["image"].get<std::string>() +
                         " has no georeferencing (no geotransform): give texel_size as a number");
  return std::nullopt;
}

std::optional<GeoHeightBand> georaster_height_band(const Job& job) {
  const nlohmann::json& h = job.doc["height"];
  if (!h.contains("image")) return std::nullopt;
  const std::string image = h["image"].get<std::string>();
  const std::optional<GeoRasterInfo> geo = checked_georaster(job);
  if (!geo) return std::nullopt;
  const ChannelSelector channel = channel_selector(h.contains("channel") ? h["channel"] : nlohmann::json());
  // Bands by index (0-based, like channels), by description, or by colour as OpenImageIO names a channel
  // ("R", "G", "B", "A": an RGB TIFF reads alike through either reader).
  int band = -1;
  std::string names;
  for (int b = 0; b < geo->bands; ++b)
    names += (b ? ", " : "") + (geo->band_names[b].empty() ? std::to_string(b) : geo->band_names[b]) +
             (geo->band_colours[b].empty() ? "" : " (" + geo->band_colours[b] + ")");
  const bool image_values = values_through_image_reader(*geo);
  std::optional<ImageInfo> image_info;  // a PNG's channels, as OpenImageIO reads them
  if (image_values) {
    image_info = probe_image(job.resolve(image), site(job, "/height/image"));
    band = find_channel(*image_info, channel, job.resolve(image), site(job, "/height/channel"));
  } else if (geo->palette) {
    // A palette image reads its colours' red, as OpenImageIO's channel 0 or "R" (docs/heights.md); the
    // palette's other colours are not read through GDAL.
    const int* index = std::get_if<int>(&channel);
    const std::string* name = std::get_if<std::string>(&channel);
    if (!(std::holds_alternative<FirstNonAlphaChannel>(channel) || (index && *index == 0) ||
          (name && *name == "R")))
      throw InputError(
          job.file.string(), "/height/channel",
          job.resolve(image).string() +
              ": is a palette image read through GDAL (georeferenced, or a world file beside it), "
              "whose heights are its palette's red (channel 0 or \"R\"): for another colour, "
              "expand it first (gdal_translate -expand rgb)");
    band = 0;
  } else if (std::holds_alternative<FirstNonAlphaChannel>(channel)) {
    // GDAL names a band's role by its colour interpretation ("A": alpha).
    band = 0;
    for (int b = geo->bands - 1; b >= 0; --b)
      if (geo->band_colours[std::size_t(b)] != "A") band = b;
  } else if (const int* index = std::get_if<int>(&channel)) {
    if (*index < geo->bands) band = *index;
  } else {
    for (int b = 0; b < geo->bands && band < 0; ++b)
      if (geo->band_names[b] == std::get<std::string>(channel)) band = b;
    for (int b = 0; b < geo->bands && band < 0; ++b)
      if (geo->band_colours[b] == std::get<std::string>(channel)) band = b;
  }
  if (band < 0)
    throw InputError(job.file.string(), "/height/channel",
                     job.resolve(image).string() + ": has no such band (it has " +
                         std::to_string(geo->bands) + ": " + names + ")");
  GeoHeightBand out;
  out.file = job.resolve(image);
  out.band = band;
  out.image_values = image_values;
  out.width = geo->width;
  out.height = geo->height;
  out.nodata = image_values ? std::nullopt : geo->nodata[std::size_t(band)];
  if (!image_values)
    if (const std::string gap = uncovered_problem(*geo, band); !gap.empty())
      throw InputError(job.file.string(), "/height/image", out.file.string() + ": " + gap);
  out.source.reader = image_values ? "OpenImageIO, placed by GDAL" : "GDAL";
  out.source.format = geo->driver;
  out.source.geographic = geo->geographic;
  if (image_info) {
    if (image_info->channels > 1) {
      std::string channels;
      for (const std::string& n : image_info->channel_names) channels += (channels.empty() ? "" : ", ") + n;
      out.source.channel = "channel " + image_info->channel_names[std::size_t(band)] + " of " + channels;
    }
  } else if (geo->bands > 1) {
    out.source.channel = "band " + std::to_string(band + 1) + " of " + std::to_string(geo->bands);
  }
  // A PNG declares no scale, offset or unit.
  const std::size_t gb = image_values ? 0 : std::size_t(band);
  out.source.file_scale = image_values ? 1.0 : geo->scale[gb];
  out.source.file_offset = image_values ? 0.0 : geo->offset[gb];
  out.source.pixel_unit = geo->geographic ? "" : geo->linear_unit;
  out.source.pixel_unit_metres = geo->geographic ? 1.0 : geo->linear_unit_metres;
  out.source.height_unit = image_values ? "" : geo->unit_types[gb];
  Georeference& georeference = out.georeference;
  georeference.geotransform = local_geotransform(job_texel_size(job));
  georeference.from_file = geo->has_geotransform;
  georeference.crs_wkt = geo->crs_wkt;
  georeference.crs_name = geo->crs_name;
  if (geo->has_geotransform) georeference.geotransform = geo->geotransform;
  if (geo->has_geotransform && !geo->crs_wkt.empty()) {
    const std::array<double, 6>& g = georeference.geotransform;
    const double x = g[0] + 0.5 * geo->width * g[1] + 0.5 * geo->height * g[2];
    const double y = g[3] + 0.5 * geo->width * g[4] + 0.5 * geo->height * g[5];
    const auto lonlat = crs_to_lonlat(geo->crs_wkt, x, y);
    const auto gamma = grid_convergence(geo->crs_wkt, x, y);
    if (lonlat && gamma) {
      georeference.has_site = true;
      georeference.site_longitude = (*lonlat)[0], georeference.site_latitude = (*lonlat)[1];
      georeference.site_convergence = *gamma;
      if (const auto k = grid_scale_factor(geo->crs_wkt, x, y)) georeference.site_scale = *k;
    }
  }
  return out;
}

bool image_geographic(const Job& job) {
  const std::optional<GeoRasterInfo> geo = checked_georaster(job);
  return geo && geo->geographic;
}

HeightField load_image_field(const Job& job, double texel_size, Wrap wrap, Georeference& georeference,
                             HeightSource& source, const std::function<void(double)>& progress) {
  const nlohmann::json& h = job.doc["height"];
  const std::string image = h["image"].get<std::string>();
  Plane plane;
  std::optional<double> file_nodata;
  if (std::optional<GeoHeightBand> geo = georaster_height_band(job)) {
    plane = geo->image_values
                ? read_image_channel(geo->file, geo->band, site(job, "/height/image"),
                                     site(job, "/height/channel"), progress)
                : read_georaster_band(geo->file, geo->band, site(job, "/height/image"), progress);
    source.reader = geo->source.reader;
    source.format = geo->source.format;
    source.geographic = geo->source.geographic;
    source.channel = geo->source.channel;
    source.file_scale = geo->source.file_scale, source.file_offset = geo->source.file_offset;
    source.pixel_unit = geo->source.pixel_unit, source.pixel_unit_metres = geo->source.pixel_unit_metres;
    source.height_unit = geo->source.height_unit;
    file_nodata = geo->nodata;
    georeference = std::move(geo->georeference);
  } else {
    const ChannelSelector channel = channel_selector(h.contains("channel") ? h["channel"] : nlohmann::json());
    const ImageInfo info = probe_image(job.resolve(image), site(job, "/height/image"));
    plane = read_image_channel(job.resolve(image), channel, site(job, "/height/image"),
                               site(job, "/height/channel"), progress);
    source.reader = "OpenImageIO";
    source.format = info.format;
    source.unread = info.unread;
    if (info.channels > 1) {
      std::string names;
      for (const std::string& n : info.channel_names) names += (names.empty() ? "" : ", ") + n;
      const int c = find_channel(info, channel, job.resolve(image), site(job, "/height/channel"));
      source.channel = "channel " + info.channel_names[std::size_t(c)] + " of " + names;
    }
  }
  source.sample_type = plane.sample_type;
  source.integer = plane.integer;
  HeightField field;
  field.width = plane.width;
  field.height = plane.height;
  field.texel_size = texel_size;
  field.wrap = wrap;
  field.z = std::move(plane.values);
  source.nodata_note = apply_height_nodata(job, image, field, georeference, file_nodata);
  return field;
}

std::string nodata_inside_heights(const HeightField& field, float value) {
  const std::vector<float>& z = field.z;
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  std::size_t count = 0;
  for (const float v : z) {
    if (v == value)
      ++count;
    else if (std::isfinite(v))
      lo = std::min(lo, v), hi = std::max(hi, v);
  }
  if (count < 8 || !(lo < value && value < hi)) return "";
  std::size_t thin = 0;
  const int W = field.width, H = field.height;
  for (int j = 0; j < H; ++j)
    for (int i = 0; i < W; ++i) {
      if (z[field.index(i, j)] != value) continue;
      const auto other = [&](int a, int b) {
        if (a < 0 || b < 0 || a >= W || b >= H) return false;
        const float v = z[field.index(a, b)];
        return v != value && std::isfinite(v);
      };
      thin += other(i - 1, j) || other(i + 1, j) || other(i, j - 1) || other(i, j + 1) ? 1 : 0;
    }
  if (double(thin) < 0.9 * double(count)) return "";
  return "the NoData value " + num(value) + " lies inside the other heights' range (" + num(lo) + " .. " +
         num(hi) + ") and its " + std::to_string(count) +
         " texels lie in thin lines and specks, not blocks: real heights taken for holes? A NoData value "
         "outside the heights' range (gdal_translate -a_nodata -9999 after setting the holes to it) keeps "
         "them";
}

std::string apply_height_nodata(const Job& job, const std::string& source, HeightField& field,
                                Georeference& georeference, std::optional<double> file_nodata) {
  const nlohmann::json& h = job.doc["height"];
  // The file's NoData value (a NaN one is caught as NaN) and the job's nodata_value both mark holes.
  const std::optional<float> nodata = nodata_value(h);
  const bool file_value = file_nodata && !std::isnan(*file_nodata);
  const bool fill = h.value("nodata", "error") == "fill";
  std::string note;
  if (fill && (file_value || nodata))
    note = nodata_inside_heights(field, file_value ? float(*file_nodata) : *nodata);
  std::size_t file_holes = 0;
  if (file_value) {
    const float v = float(*file_nodata);
    for (float& z : field.z)
      if (z == v) z = std::numeric_limits<float>::quiet_NaN(), ++file_holes;
  }
  const NodataScan scan = scan_nodata(field, nodata);
  if (scan.count == 0) return "";
  if (!fill) {
    const float first = field.z[field.index(scan.first_i, scan.first_j)];
    std::string what = std::isnan(first) ? "NaN" : std::isinf(first) ? "infinite" : "nodata_value";
    if (file_value && std::isnan(first)) what = "NaN or the file's NoData value (" + num(*file_nodata) + ")";
    throw InputError(job.file.string(), "/height/image",
                     source + ": texel (" + std::to_string(scan.first_i) + ", " +
                         std::to_string(scan.first_j) + ") is " + what + " (" + std::to_string(scan.count) +
                         " of " + std::to_string(field.texel_count()) +
                         " texels have no valid height); set \"nodata\": \"fill\" to fill the holes");
  }
  georeference.holes.assign(field.texel_count(), 0);
  for (std::size_t t = 0; t < field.z.size(); ++t)
    georeference.holes[t] = !std::isfinite(field.z[t]) || (nodata && field.z[t] == *nodata);
  if (!fill_nodata(field, nodata))
    throw InputError(job.file.string(), "/height/image", source + ": no texel has a valid height");
  return note;
}

void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field,
                      std::vector<Rgb>& texels) {
  const nlohmann::json& v = job.doc.at(nlohmann::json::json_pointer(pointer));
  if (v.is_number()) {
    const float x = v.get<float>();
    std::fill(texels.begin(), texels.end(), Rgb{x, x, x});
    return;
  }
  if (v.is_array()) {
    std::fill(texels.begin(), texels.end(), Rgb{v[0].get<float>(), v[1].get<float>(), v[2].get<float>()});
    return;
  }
  const std::string image = v["image"].get<std::string>();
  RgbImage rgb = read_rgb_image(job.resolve(image), v.value("colorspace", std::string()),
                                site(job, pointer + "/image"), site(job, pointer + "/colorspace"));
  if (rgb.width != field.width || rgb.height != field.height)
    throw InputError(job.file.string(), pointer + "/image",
                     image + ": is " + std::to_string(rgb.width) + "x" + std::to_string(rgb.height) +
                         ", the height field is " + std::to_string(field.width) + "x" +
                         std::to_string(field.height));
  const float scale = v.value("scale", 1.0f);
  // An albedo is a reflectance: [0, 1], as a number albedo (job.schema.json albedo_rgb), after the scale.
  const bool reflectance = pointer == "/surface/albedo";
  std::vector<Rgb> pixels = std::move(rgb.pixels);  // scaled in place: no second full-size copy
  for (std::size_t t = 0; t < pixels.size(); ++t) {
    const Rgb p = pixels[t];
    const std::string where = image + ": pixel (" + std::to_string(t % std::size_t(field.width)) + ", " +
                              std::to_string(t / std::size_t(field.width)) + ")";
    if (!std::isfinite(p.r) || !std::isfinite(p.g) || !std::isfinite(p.b) || p.r < 0 || p.g < 0 || p.b < 0)
      throw InputError(job.file.string(), pointer + "/image", where + " is negative or not finite");
    pixels[t] = p * scale;
    const Rgb s = pixels[t];
    // An albedo is a reflectance; an emission a radiance, at most kMaxRadiance as a number emission is.
    const float most = reflectance ? 1.0f : float(kMaxRadiance);
    if (!(s.r <= most && s.g <= most && s.b <= most)) {
      char value[96];
      std::snprintf(value, sizeof value, " is (%g, %g, %g) after the scale", double(s.r), double(s.g),
                    double(s.b));
      throw InputError(job.file.string(), pointer + "/image",
                       where + value +
                           (reflectance ? "; an albedo lies in [0, 1] (a reflectance)"
                                        : "; an emission lies in [0, 1e9], as a number emission does"));
    }
  }
  texels = std::move(pixels);
}

void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field, SurfaceMap& map) {
  const nlohmann::json& v = job.doc.at(nlohmann::json::json_pointer(pointer));
  if (v.is_number() || v.is_array()) {
    const Rgb x = v.is_number() ? Rgb{v.get<float>(), v.get<float>(), v.get<float>()}
                                : Rgb{v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    map.assign(field.texel_count(), x);
    return;
  }
  std::vector<Rgb> texels(field.texel_count());
  load_surface_map(job, pointer, field, texels);
  map.assign(std::move(texels));
}

void load_lighting(const Job& job, Scene& scene) {
  const nlohmann::json env = job.doc.value("environment", nlohmann::json::object());
  EnvironmentLoadOptions options;
  options.job_file = job.file.string();
  EnvironmentLighting lighting = load_environment(env, job.base_dir, options);
  scene.environment = std::move(lighting.environment);
  scene.lights = std::move(lighting.lights);
}

}  // namespace hfbake
