#include "cli/horizon_command.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>
#include <utility>

#include "cli/scene_loader.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "core/vec.hpp"
#include "io/crs_geodesy.hpp"
#include "io/georaster_input.hpp"
#include "io/preview.hpp"
#include "terrain/horizon_plot.hpp"
#include "terrain/point_horizon.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

std::string num(double v, const char* format = "%.10g") {
  char buf[40];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// "X,Y" as two finite numbers.
std::optional<std::array<double, 2>> parse_pair(const std::string& text) {
  const auto comma = text.find(',');
  if (comma == std::string::npos) return std::nullopt;
  double v[2];
  const std::string parts[2] = {text.substr(0, comma), text.substr(comma + 1)};
  for (int p = 0; p < 2; ++p) {
    std::size_t used = 0;
    try {
      v[p] = std::stod(parts[p], &used);
    } catch (const std::exception&) {
      return std::nullopt;
    }
    while (used < parts[p].size() && parts[p][used] == ' ') ++used;
    if (used != parts[p].size() || !std::isfinite(v[p])) return std::nullopt;
  }
  return std::array<double, 2>{v[0], v[1]};
}

struct Profile {
  std::array<double, 6> g{};
  double map_x = 0, map_y = 0, surface = 0, observer = 0;
  std::optional<EarthCurvature> curvature;
  std::string crs_name, unit;
  bool geographic = false;
  double convergence = 0;  // radians: true north's azimuth in the grid
  double map_scale = 1;    // the projected CRS's point scale factor there (1: none known)
  std::vector<HorizonRay> rays;
  std::vector<std::string> warnings;  // about the heights, one line each
};

// What the command says about a band's heights when it is given no --height-scale or --height-offset: a
// declared scale or offset it does not apply, and heights in another unit than the pixels' (as validate says
// them for a job, with the arguments that apply them).
std::vector<std::string> height_warnings(const HorizonOptions& o, const GeoRasterInfo& info) {
  std::vector<std::string> w;
  if (o.height_scale || o.height_offset) return w;
  const std::size_t b = std::size_t(o.band);
  const double scale = info.scale[b], offset = info.offset[b];
  if (scale != 1 || offset != 0)
    w.push_back("the file declares scale " + num(scale, "%.6g") + " and offset " + num(offset, "%.6g") +
                ", not applied (heights are the stored values): --height-scale " + num(scale, "%.6g") +
                " --height-offset " + num(offset, "%.6g") + " apply them");
  const std::string pixel_unit = info.geographic ? "metre" : info.linear_unit;
  const double pixel_metres = info.geographic ? 1.0 : info.linear_unit_metres;
  const double ratio = height_unit_ratio(info.unit_types[b], pixel_metres);
  if (ratio != 1)
    w.push_back("the band's heights are in " + info.unit_types[b] + " and its pixels in " + pixel_unit +
                ": elevations come out too " + (ratio > 1 ? "low" : "high") + "; give --height-scale " +
                num(ratio, "%.6g"));
  else if (!info.geographic && pixel_metres != 1.0 && info.unit_types[b].empty())
    w.push_back("the band declares no unit: heights taken in " + pixel_unit +
                "; heights in metres need --height-scale " + num(1 / pixel_metres, "%.6g"));
  return w;
}

std::string to_csv(const Profile& p) {
  std::string s = "azimuth_deg,elevation_deg,distance,caster_x,caster_y,caster_z\n";
  for (const HorizonRay& r : p.rays) {
    s += num(r.azimuth_deg, "%.6f");
    if (r.found) {
      const double cx = p.g[0] + (r.x + 0.5) * p.g[1], cy = p.g[3] + (r.y + 0.5) * p.g[5];
      for (const std::string& field :
           {num(r.elevation_deg, "%.6f"), num(r.distance, "%.4f"), num(cx), num(cy), num(r.z, "%.4f")}) {
        s += ',';
        s += field;
      }
    } else {
      s += ",,,,,";
    }
    s += "\n";
  }
  return s;
}

std::string to_json(const HorizonOptions& o, const Profile& p) {
  nlohmann::json doc;
  doc["dem"] = o.dem;
  doc["crs"] = p.crs_name;
  doc["point"] = {{"x", p.map_x}, {"y", p.map_y}, {"surface_z", p.surface}, {"observer_z", p.observer}};
  doc["distance_unit"] = p.unit;
  doc["map_scale_factor"] = p.map_scale;  // map units per ground unit at the point (a projected CRS's)
  doc["azimuth"] = p.crs_name.empty() ? "compass: degrees clockwise from the raster's north (no CRS)"
                                      : "compass: degrees clockwise from true north";
  doc["grid_convergence_deg"] = p.convergence * 180 / kPi;
  if (p.curvature)
    doc["curvature"] = {{"refraction", p.curvature->refraction},
                        {"meridian_radius", p.curvature->meridian_radius},
                        {"normal_radius", p.curvature->normal_radius}};
  else
    doc["curvature"] = nullptr;
  nlohmann::json rays = nlohmann::json::array();
  for (const HorizonRay& r : p.rays) {
    nlohmann::json ray = {{"azimuth_deg", r.azimuth_deg}, {"found", r.found}};
    if (r.found) {
      ray["elevation_deg"] = r.elevation_deg;
      ray["distance"] = r.distance;
      ray["caster"] = {p.g[0] + (r.x + 0.5) * p.g[1], p.g[3] + (r.y + 0.5) * p.g[5], r.z};
    } else {
      ray["elevation_deg"] = nullptr;
    }
    rays.push_back(std::move(ray));
  }
  doc["rays"] = std::move(rays);
  return doc.dump(1) + "\n";
}

Profile compute(const HorizonOptions& o) {
  auto fail = [&](const std::string& where, const std::string& what) {
    throw InputError(o.dem, where, what);
  };
  if (o.format != "csv" && o.format != "json") fail("--format", "is " + o.format + ", not csv or json");
  if (!(o.directions >= 1 && o.directions <= 1000000)) fail("--directions", "must be in [1, 1000000]");
  if (!(o.plot_size >= 64 && o.plot_size <= 8192)) fail("--plot-size", "must be in [64, 8192]");
  if (!(std::isfinite(o.observer_height) && o.observer_height >= 0))
    fail("--observer-height", "must be a finite height >= 0");
  if (o.refraction && !(std::isfinite(*o.refraction) && *o.refraction > -1 && *o.refraction < 1))
    fail("--refraction", "must be in (-1, 1)");
  if (o.height_scale && !(std::isfinite(*o.height_scale) && std::fabs(*o.height_scale) <= 1e6))
    fail("--height-scale", "must be a finite number in [-1e6, 1e6]");
  if (o.height_offset && !(std::isfinite(*o.height_offset) && std::fabs(*o.height_offset) <= 1e9))
    fail("--height-offset", "must be a finite number in [-1e9, 1e9]");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(o.dem, ec))
    fail("", std::filesystem::exists(o.dem, ec) ? "not a regular file (a folder, a device or a pipe)"
                                                : "no such file");
  const std::optional<GeoRasterInfo> info = probe_georaster(o.dem);
  if (!info)
    fail("", "not a raster GDAL reads with georeferencing (a geotransform): --at needs map coordinates");
  if (!info->has_geotransform) fail("", "has no geotransform: --at needs map coordinates");
  Profile p;
  p.g = info->geotransform;
  const auto& g = p.g;
  if (!north_up(g)) fail("", "is rotated or sheared; warp it north-up first (gdalwarp)");
  if (const std::string problem = geographic_unit_problem(*info); !problem.empty()) fail("", problem);
  if (o.band < 0 || o.band >= info->bands)
    fail("--band", "is " + std::to_string(o.band) + " but the raster has " + std::to_string(info->bands) +
                       " band(s) (0-based)");
  if (const std::string gap = uncovered_problem(*info, o.band); !gap.empty()) fail("", gap);
  p.crs_name = info->crs_name;
  p.geographic = info->geographic;
  p.unit = info->geographic ? "metre" : info->linear_unit;

  const std::optional<std::array<double, 2>> at = parse_pair(o.at);
  if (!at) fail("--at", "is \"" + o.at + "\", not X,Y (two numbers)");
  std::array<double, 2> xy = *at;
  if (o.lonlat) {
    if (info->crs_wkt.empty()) fail("--lonlat", "the raster has no CRS to transform longitude/latitude into");
    if (std::abs((*at)[1]) > 90) fail("--at", "latitude " + num((*at)[1]) + " is outside [-90, 90]");
    if (std::abs((*at)[0]) > 180) fail("--at", "longitude " + num((*at)[0]) + " is outside [-180, 180]");
    const auto moved = lonlat_to_crs(info->crs_wkt, (*at)[0], (*at)[1]);
    if (!moved) fail("--at", "PROJ cannot transform " + o.at + " (WGS 84) into " + info->crs_name);
    xy = *moved;
    // A geographic raster's longitudes may run past 180 (across the antimeridian, or 0..360): the same
    // meridian a whole turn away, where it lies on the raster.
    if (info->geographic) {
      const double xa = std::min(g[0], g[0] + info->width * g[1]),
                   xb = std::max(g[0], g[0] + info->width * g[1]);
      for (const double turn : {-360.0, 360.0})
        if (!(xy[0] >= xa && xy[0] <= xb) && xy[0] + turn >= xa && xy[0] + turn <= xb) xy[0] += turn;
    }
  }
  p.map_x = xy[0], p.map_y = xy[1];

  PointHorizonQuery q;
  q.x = (xy[0] - g[0]) / g[1] - 0.5;
  q.y = (xy[1] - g[3]) / g[5] - 0.5;
  q.observer_height = o.observer_height;
  q.directions = o.directions;
  const double x0 = g[0] + 0.5 * g[1], x1 = g[0] + (info->width - 0.5) * g[1];
  const double y0 = g[3] + 0.5 * g[5], y1 = g[3] + (info->height - 0.5) * g[5];
  const std::string where = num(xy[0]) + "," + num(xy[1]);
  if (!(q.x >= 0 && q.y >= 0 && q.x <= info->width - 1 && q.y <= info->height - 1)) {
    const auto full = [](double v) { return num(v, "%.15g"); };  // a point just outside is not on the range
    fail("--at", full(xy[0]) + "," + full(xy[1]) + " is outside the surface: its texel centres span x " +
                     full(std::min(x0, x1)) + ".." + full(std::max(x0, x1)) + ", y " +
                     full(std::min(y0, y1)) + ".." + full(std::max(y0, y1)));
  }

  // The ground frame and, with curvature, the Earth's radii at the point.
  std::optional<CrsEarth> earth = info->crs_wkt.empty() ? std::nullopt : crs_earth(info->crs_wkt);
  Ellipsoid ellipsoid;  // a sphere of the mean radius when the CRS names no ellipsoid
  double lat = 0;
  if (earth)
    ellipsoid = {earth->semi_major / earth->metres_per_unit, earth->semi_minor / earth->metres_per_unit};
  if (info->geographic) {
    if (!earth) fail("", "has a geographic CRS without an ellipsoid GDAL can read");
    lat = xy[1] * kPi / 180;
    if (!(std::abs(xy[1]) < 89.9)) fail("--at", "latitude " + num(xy[1]) + " is too near a pole");
    const double rad = kPi / 180;
    q.frame = {g[1] * rad * ellipsoid.prime_vertical_radius(lat) * std::cos(lat),
               g[5] * rad * ellipsoid.meridian_radius(lat)};
  } else {
    q.frame = {g[1], g[5]};
    if (!info->crs_wkt.empty()) {
      const std::optional<double> gamma = grid_convergence(info->crs_wkt, xy[0], xy[1]);
      if (!gamma) fail("--at", "PROJ cannot find true north at " + where + " in " + info->crs_name);
      q.frame.convergence = *gamma;
      // Distances on the ground where the CRS is far from true scale (as a bake warns of a field): a
      // conformal projection's map units are k times the ground's near the point (PROJ's point scale
      // factor), so the frame takes map distances divided by k and the horizons' elevations and distances
      // are the ground's (docs/gis.md, Map scale). Within 1 % of true scale, map units, as a bake takes them.
      if (const std::optional<double> k = grid_scale_factor(info->crs_wkt, xy[0], xy[1]); k) {
        p.map_scale = *k;
        if (far_from_true_scale(*k) && std::isfinite(*k) && *k > 0)
          q.frame.east_per_x /= *k, q.frame.north_per_y /= *k;
      }
    }
    if (earth && o.curvature.value_or(false)) {
      const auto lonlat = crs_to_lonlat(info->crs_wkt, xy[0], xy[1]);
      if (!lonlat) fail("--at", "PROJ cannot find the latitude of " + where + " in " + info->crs_name);
      lat = (*lonlat)[1] * kPi / 180;
    }
  }
  if (o.refraction && !o.curvature.value_or(info->geographic))
    fail("--refraction", "applies with Earth curvature only (--curvature)");
  if (o.curvature.value_or(info->geographic))
    q.curvature = EarthCurvature::at(ellipsoid, lat, o.refraction.value_or(kDefaultRefraction));
  p.curvature = q.curvature;
  p.convergence = q.frame.convergence;

  // The heights, once every argument is checked.
  Plane plane = read_georaster_band(o.dem, o.band, InputSite{"", ""});
  HeightField field;
  field.width = plane.width, field.height = plane.height, field.wrap = Wrap::clamp;
  field.z = std::move(plane.values);
  if (const std::optional<double> nodata = info->nodata[std::size_t(o.band)]; nodata && !std::isnan(*nodata))
    for (float& z : field.z)
      if (z == float(*nodata)) z = std::nanf("");
  if (o.height_scale || o.height_offset) {
    const double a = o.height_scale.value_or(1.0), b = o.height_offset.value_or(0.0);
    for (float& z : field.z) z = float(double(z) * a + b);
  }
  p.warnings = height_warnings(o, *info);
  const std::optional<double> z = surface_height(field, q.x, q.y);
  if (!z) fail("--at", where + " is on NoData (a texel around it has no height)");
  p.surface = *z;
  p.observer = *z + o.observer_height;
  p.rays = point_horizon(field, q);
  return p;
}

}  // namespace

int run_horizon(const HorizonOptions& o) {
  try {
    // The outputs never replace the DEM, nor each other; each is written whole or not at all (a
    // temporary renamed into place, docs/output_folders.md), the previous file kept until then.
    // The DEM is every file GDAL reads for it (a VRT's sources, side files: io/georaster_input.hpp).
    std::error_code ec;
    std::vector<fs::path> dem;
    for (const fs::path& f : raster_files(o.dem)) dem.push_back(fs::weakly_canonical(fs::absolute(f), ec));
    for (const auto& [option, file] :
         {std::pair<std::string, std::string>{"--out", o.out}, {"--plot", o.plot}}) {
      if (file.empty()) continue;
      if (const std::string why = named_output_problem(file); !why.empty())
        throw InputError(file, option, why);
      const fs::path out = fs::weakly_canonical(fs::absolute(file), ec);
      if (out == dem.front())
        throw InputError(o.dem, option, "is the DEM this command reads: give the output another name");
      for (const fs::path& f : dem)
        if (out == f)
          throw InputError(
              o.dem, option,
              "is " + f.string() + ", which GDAL reads for the DEM: give the output another name");
    }
    if (!o.out.empty() && !o.plot.empty() &&
        fs::weakly_canonical(fs::absolute(o.out), ec) == fs::weakly_canonical(fs::absolute(o.plot), ec))
      throw InputError(o.dem, "--plot", "is the --out file too: give each output its own name");
    const Profile p = compute(o);
    for (const std::string& w : p.warnings)
      std::fprintf(stderr, "hfbake: warning: %s: %s\n", o.dem.c_str(), w.c_str());
    const std::string text = o.format == "json" ? to_json(o, p) : to_csv(p);
    const auto write = [](const std::string& file, const std::string& option, const std::string& bytes) {
      try {
        write_named_output(file, bytes);
      } catch (const std::system_error& e) {
        throw InputError(file, option, "cannot write the file: " + e.code().message());
      }
    };
    if (!o.plot.empty()) {
      PolarPlotGeometry geometry;
      geometry.size = o.plot_size;
      write(o.plot, "--plot", encode_png(o.plot_size, o.plot_size, 3, horizon_polar_plot(p.rays, geometry)));
    }
    if (o.out.empty()) {
      std::fputs(text.c_str(), stdout);
      return 0;
    }
    write(o.out, "--out", text);
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "hfbake: error: %s\n", e.line().c_str());
    return 2;
  }
}

}  // namespace hfbake
