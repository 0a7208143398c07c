#include "methods/sun/sun.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"
#include "methods/p1/p1.hpp"
#include "methods/sun/clear_sky.hpp"
#include "methods/sun/solar_position.hpp"

namespace hfbake {

namespace {

// Where an entry gives no latitude and longitude, and no CRS gives them.
constexpr const char* kUnplaced = "required: the height field has no CRS that places it on the Earth";

const std::vector<std::string>& sun_layer_names() {
  static const std::vector<std::string> names = {"irradiation", "beam", "sky", "sun_hours"};
  return names;
}

// A local date and time "YYYY-MM-DDTHH:MM" or "YYYY-MM-DDTHH:MM:SS" as the Julian date (UT) at `offset`
// hours east of UTC; nullopt when it is not one.
std::optional<double> parse_local_time(const std::string& s, double offset) {
  const char* form = "dddd-dd-ddTdd:dd:dd";
  if (s.size() != 16 && s.size() != 19) return std::nullopt;
  for (std::size_t k = 0; k < s.size(); ++k)
    if (form[k] == 'd' ? !(s[k] >= '0' && s[k] <= '9') : s[k] != form[k]) return std::nullopt;
  int y, mo, d, h, mi, n = 0;
  double sec = 0;
  if (s.size() == 16) {
    if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d%n", &y, &mo, &d, &h, &mi, &n) != 5 || n != 16)
      return std::nullopt;
  } else if (s.size() == 19) {
    int si;
    if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &y, &mo, &d, &h, &mi, &si, &n) != 6 || n != 19)
      return std::nullopt;
    if (si > 59) return std::nullopt;
    sec = si;
  } else {
    return std::nullopt;
  }
  if (!sun::valid_date(y, mo, d) || h > 23 || mi > 59 || s[4] != '-' || s[7] != '-') return std::nullopt;
  return sun::julian_date(y, mo, d, h + mi / 60.0 + sec / 3600 - offset);
}

// A RunControl reporting into [begin, begin + span) of the caller's progress.
RunControl part_of(const RunControl& rc, double begin, double span) {
  RunControl sub;
  sub.cancel = rc.cancel;
  if (rc.progress) sub.progress = [&rc, begin, span](double x) { rc.report(begin + span * x); };
  return sub;
}

bool wants(const SunConfig& c, const char* layer) {
  return std::find(c.layers.begin(), c.layers.end(), layer) != c.layers.end();
}

P1Params horizon_params(const SunConfig& c) {
  P1Params p;
  p.directions = c.directions;
  p.near_radius = c.near_radius;
  p.far_field = c.far_field;
  return p;
}

// The sky term's p1 bake: its direct light alone, under the isotropic upper-hemisphere sky (bake_sun).
P1Params sky_params(const SunConfig& c) {
  P1Params p = horizon_params(c);
  p.ao = p.vsky = false;
  p.direct = true;
  p.lights = false;
  return p;
}

}  // namespace

SunConfig read_sun_config(Params& in, const FieldShape& field, bool placed) {
  SunConfig c;
  c.file = in.file(), c.pointer = in.pointer();
  if (in.has("latitude")) c.latitude = in.number("latitude", 0, -89.9, 89.9);
  if (in.has("longitude")) c.longitude = in.number("longitude", 0, -180, 180);
  if (c.latitude.has_value() != c.longitude.has_value())
    in.fail(c.latitude ? "longitude" : "latitude", "required with the other of latitude, longitude");
  if (!c.latitude && !placed) in.fail("latitude", kUnplaced);
  if (!in.has("utc_offset"))
    in.fail("utc_offset", "required: the hours the start and end times are ahead of UTC (0: UTC)");
  const double offset = in.number("utc_offset", 0, -14, 14);
  double jd[2];
  const char* keys[2] = {"start", "end"};
  for (int t = 0; t < 2; ++t) {
    const std::optional<std::string> text = in.text(keys[t], 19);
    if (!text) in.fail(keys[t], "required: a local date and time, \"2026-06-21T00:00\"");
    const std::optional<double> parsed = parse_local_time(*text, offset);
    if (!parsed)
      in.fail(keys[t], "must be a date and time as \"YYYY-MM-DDTHH:MM\" or \"YYYY-MM-DDTHH:MM:SS\"");
    jd[t] = *parsed;
  }
  c.start_jd = jd[0], c.end_jd = jd[1];
  const double step_minutes = in.number("step_minutes", 15, 0.1, 1440);
  c.step_hours = step_minutes / 60;
  const double range_minutes = (c.end_jd - c.start_jd) * 1440;
  if (!(range_minutes > 0)) in.fail("end", "must be after start");
  const double steps = std::round(range_minutes / step_minutes);
  if (std::abs(steps * step_minutes - range_minutes) > 1e-3)
    in.fail("step_minutes", "must divide end - start (" + std::to_string(range_minutes) + " minutes)");
  if (steps > 1e6) in.fail("step_minutes", "makes more than 1000000 steps of end - start");
  c.linke_turbidity = in.number("linke_turbidity", c.linke_turbidity, 1, 10);
  c.solar_constant = in.number("solar_constant", c.solar_constant, 1000, 1500);
  c.directions = in.integer("directions", c.directions, 1, 4096);
  c.near_radius = in.number("near_radius", c.near_radius, 1, 64);
  c.layers = in.layers(sun_layer_names(), {"irradiation", "sun_hours"});
  c.far_field = read_field_wide_far_field(in, field);
  return c;
}

std::vector<SunStep> sun_steps(const SunConfig& c, double latitude, double longitude, double convergence,
                               double east_x, double north_y) {
  std::vector<SunStep> steps;
  const long n = std::lround((c.end_jd - c.start_jd) * 24 / c.step_hours);
  for (long k = 0; k < n; ++k) {
    const double jd = c.start_jd + (double(k) + 0.5) * c.step_hours / 24;  // the step's midpoint
    const sun::SolarPosition p = sun::solar_position(jd, latitude, longitude);
    if (p.elevation <= 0) continue;
    SunStep s;
    s.elevation = p.elevation;
    s.compass_azimuth = p.azimuth;
    const double grid = p.azimuth + convergence;  // clockwise from the grid's north
    s.azimuth = std::atan2(std::cos(grid) * north_y, std::sin(grid) * east_x);
    s.direction = {std::cos(p.elevation) * std::cos(s.azimuth), std::cos(p.elevation) * std::sin(s.azimuth),
                   std::sin(p.elevation)};
    s.g0 = c.solar_constant / (p.distance_au * p.distance_au);
    s.air_mass = sun::relative_air_mass(p.elevation);
    s.diffuse = sun::diffuse_horizontal(s.g0, p.elevation, c.linke_turbidity);
    s.hours = c.step_hours;
    steps.push_back(s);
  }
  return steps;
}

SunPlace sun_place(const SunConfig& c, const Scene& scene) {
  const Georeference& g = scene.georeference;
  SunPlace p;
  if (c.latitude) {
    p.latitude = *c.latitude, p.longitude = *c.longitude;
  } else if (g.has_site) {
    p.latitude = g.site_latitude, p.longitude = g.site_longitude, p.from_crs = true;
  } else {
    throw InputError(c.file, c.pointer + "/latitude", kUnplaced);
  }
  p.convergence = g.has_site ? g.site_convergence : 0.0;
  p.east_x = g.geotransform[1] < 0 ? -1 : 1, p.north_y = g.geotransform[5] < 0 ? -1 : 1;
  return p;
}

std::vector<SunStep> sun_steps(const SunConfig& c, const Scene& scene) {
  const SunPlace p = sun_place(c, scene);
  return sun_steps(c, p.latitude, p.longitude, p.convergence, p.east_x, p.north_y);
}

double sun_beam(const SunConfig& c, const SunStep& s, double z, const Vec3& n) {
  const double cos_i = dot(n, s.direction);
  if (cos_i <= 0) return 0;
  return sun::beam_normal(s.g0, s.air_mass * sun::pressure_ratio(z), c.linke_turbidity) * cos_i;
}

LayerSet bake_sun(const Scene& scene, const MethodConfig& config, const RunControl& rc) {
  const SunConfig& c = config.get<SunConfig>();
  const HeightField& f = scene.field;
  const std::size_t N = f.texel_count();
  const std::vector<SunStep> steps = sun_steps(c, scene);
  const bool beam_wanted = wants(c, "irradiation") || wants(c, "beam") || wants(c, "sun_hours");
  const bool sky_wanted = wants(c, "irradiation") || wants(c, "sky");
  // Progress: the sky's K directions and the sun's sweeps, each about one direction of work.
  const double sky_share = !sky_wanted    ? 0.0
                           : !beam_wanted ? 1.0
                                          : 1.0 / (1 + double(steps.size()) / double(c.directions));

  // Direct sun: per texel the beam irradiation (Wh/m^2) and the steps it is lit, summed in step order.
  std::vector<double> beam(beam_wanted ? N : 0);
  std::vector<float> lit(beam_wanted ? N : 0);
  double far_slack = 0;  // with a far field: the largest slack its floor left (p1_horizons_at)
  if (beam_wanted) {
    std::vector<double> azimuths;
    for (const SunStep& s : steps) azimuths.push_back(s.azimuth);
    // Flat horizons, as the sky term's (the far field's floor too).
    CoarseHeights own;
    const std::unique_ptr<p1::FloorGrid> floor = p1_floor_grid(scene, horizon_params(c), own, 0.0);
    p1_horizons_at(
        f, horizon_params(c), azimuths, part_of(rc, 0, 1 - sky_share),
        [&](int a, int i, int j, float horizon) {
          const SunStep& s = steps[std::size_t(a)];
          if (!(s.elevation > double(horizon))) return;
          const std::size_t t = f.index(i, j);
          const double e = sun_beam(c, s, f.z[t], normal_at(f, i, j).d());
          if (e <= 0) return;
          beam[t] += e * s.hours;
          lit[t] += 1;
        },
        0.0, floor.get(), &far_slack);
  }

  // The sky: an isotropic sky of radiance 1 above the astronomical horizon, lit through p1's exact
  // lighting at each texel's normal, gives E / pi = the share F of the horizontal diffuse irradiance the
  // texel receives; its irradiation is F times the model's diffuse horizontal irradiation.
  double diffuse_wh = 0;
  for (const SunStep& s : steps) diffuse_wh += s.diffuse * s.hours;
  std::vector<float> sky(sky_wanted ? N : 0);
  if (sky_wanted && diffuse_wh > 0) {
    Scene upper;
    upper.field = f;
    upper.window = scene.window;
    upper.environment = make_latlong_environment(
        4, 2, {Rgb{1, 1, 1}, Rgb{1, 1, 1}, Rgb{1, 1, 1}, Rgb{1, 1, 1}, Rgb{}, Rgb{}, Rgb{}, Rgb{}});
    P1Result r = compute_p1(upper, sky_params(c), part_of(rc, 1 - sky_share, sky_share));
    for (std::size_t t = 0; t < N; ++t) sky[t] = float(double(r.direct[3 * t]) * diffuse_wh);
    far_slack = std::max(far_slack, r.far_field_bound.value_or(0.0));
  }

  LayerSet out;
  out.width = f.width, out.height = f.height;
  for (const std::string& name : c.layers) {
    std::vector<float> v(N);
    if (name == "irradiation") {
      for (std::size_t t = 0; t < N; ++t) v[t] = float(beam[t] + double(sky[t]));
    } else if (name == "beam") {
      for (std::size_t t = 0; t < N; ++t) v[t] = float(beam[t]);
    } else if (name == "sky") {
      v = sky;
    } else if (name == "sun_hours") {
      for (std::size_t t = 0; t < N; ++t) v[t] = float(double(lit[t]) * c.step_hours);
    }
    out.adopt(name, mono_channels(), std::move(v));
  }
  out.attributes.emplace_back("hfbake:sun:units",
                              "irradiation, beam, sky: Wh/m^2 over the time range; sun_hours: hours");
  out.attributes.emplace_back("hfbake:sun:steps", std::to_string(steps.size()) + " with the sun up");
  const SunPlace place = sun_place(c, scene);
  char where[200];
  std::snprintf(where, sizeof where,
                "latitude %.6f, longitude %.6f (%s); true north at grid azimuth %.4f deg", place.latitude,
                place.longitude, place.from_crs ? "the field's centre, from its CRS" : "the job's",
                place.convergence * 180 / kPi);
  out.attributes.emplace_back("hfbake:sun:place", where);
  if (c.far_field) {
    // Certified per bake (methods/p1/far_floor.hpp): every horizon's tangent at least the exact one's and at
    // most this above it.
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", far_slack);
    out.attributes.emplace_back("hfbake:sun:far_field_bound", b);
  }
  rc.report(1.0);
  return out;
}

MethodInfo sun_method() {
  MethodInfo m;
  m.name = "sun";
  m.summary =
      "sunlight over a time range: clear-sky beam through the exact horizons at each sun position, "
      "plus diffuse sky";
  m.read = [](Params& in, const MethodContext& context) {
    const SunConfig c = read_sun_config(in, context.field, context.placed);
    return method_config(c, 0);
  };
  m.bake = bake_sun;
  m.memory_knob = "a smaller field";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& context) {
    const SunConfig& c = config.get<SunConfig>();
    // The beam and lit sums (12 bytes a texel), the sky term's copy of the heights and p1's direct (16),
    // and the sky term's p1 bake (its direct light under a non-uniform sky) or, without one, the beam's
    // horizons.
    const bool sky = wants(c, "irradiation") || wants(c, "sky");
    return 28.0 * double(context.field.width) * double(context.field.height) +
           (sky ? p1_working_bytes(context.field, sky_params(c), false)
                : p1_working_bytes(context.field, horizon_params(c)));
  };
  m.division = WorkDivision::texel_tiles;
  // A far field bounds the heights the horizons read exactly (P1Params::far_field): tiles with a halo of
  // `beyond` and the raster's coarse copy.
  m.reach = [](const MethodConfig& config) {
    return far_field_reach(config.get<SunConfig>().far_field, std::numeric_limits<double>::infinity());
  };
  m.far_cell = [](const MethodConfig& config) { return far_field_cell(config.get<SunConfig>().far_field); };
  m.division_note =
      "texel tiles with a halo of the horizons' reach (each texel's sums are its own); runs "
      "whole on the farm";
  m.reads_normals = false;  // normal_at from the heights
  m.reads_albedo = false;
  return m;
}

}  // namespace hfbake
