// The sun method against independent truth: the solar position against the published example of NREL's
// SPA (Reda & Andreas 2004) and the 2026 solstice and equinox; the clear-sky model at the zenith against its
// formulas evaluated by hand; the direct sun against a per-step computation from exact horizon marches over
// every column, row and diagonal crossing of the triangulation from each texel centre (p1_truth.hpp); the
// sky term against Liu & Jordan's (1 + cos beta) / 2 on planes.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>

#include "core/error.hpp"
#include "methods/method_table.hpp"
#include "methods/sun/clear_sky.hpp"
#include "methods/sun/solar_position.hpp"
#include "methods/sun/sun.hpp"
#include "p1_truth.hpp"

namespace {
using namespace hfbake;
constexpr double kDeg = kPi / 180;

const Layer& layer(const LayerSet& s, const char* name) {
  for (const Layer& l : s.layers)
    if (l.name == name) return l;
  throw std::runtime_error(std::string("no layer ") + name);
}

// `placed`: as for a field a CRS places on the Earth (the tests' scenes carry their place in the entry or
// test sun_steps directly).
MethodConfig sun_config(const nlohmann::json& j, const HeightField& f, bool placed = true) {
  MethodContext c;
  c.field = f;
  c.placed = placed;
  return read_method_config("sun", j, c);
}

Scene scene_of(HeightField f) {
  Scene s;
  s.field = std::move(f);
  s.georeference.geotransform = local_geotransform(s.field.texel_size);
  return s;
}

TEST(SolarPosition, SpaReferenceExample) {
  // Reda & Andreas (2004), Table A5.1: 17 October 2003, 12:30:30 at UTC-7, 39.742476 N, 105.1786 W:
  // topocentric azimuth 194.34024 degrees, elevation 39.87205 degrees before refraction (zenith 50.11162
  // with 0.016332 of refraction). The geocentric sun is 0.0024 degrees higher (parallax); the algorithm's
  // stated accuracy is 0.01 degrees.
  const double jd = sun::julian_date(2003, 10, 17, 19 + 30 / 60.0 + 30 / 3600.0);
  const sun::SolarPosition p = sun::solar_position(jd, 39.742476, -105.1786);
  EXPECT_NEAR(p.elevation / kDeg, 39.87205 + 0.0024, 0.015);
  EXPECT_NEAR(p.azimuth / kDeg, 194.34024, 0.02);
}

TEST(SolarPosition, SolsticeAndEquinox2026) {
  // The June solstice of 2026 is at 08:24 UTC on 21 June (declination = the obliquity, 23.4362 degrees);
  // the March equinox at 14:46 UTC on 20 March (declination 0; it moves 0.017 degrees an hour then).
  EXPECT_NEAR(sun::solar_position(sun::julian_date(2026, 6, 21, 8.4), 0, 0).declination / kDeg, 23.4362,
              0.01);
  EXPECT_NEAR(sun::solar_position(sun::julian_date(2026, 3, 20, 14 + 46 / 60.0), 0, 0).declination / kDeg, 0,
              0.01);
  EXPECT_DOUBLE_EQ(sun::julian_date(2000, 1, 1, 12), 2451545.0);
  // Perihelion (early January) and aphelion (early July) distances.
  EXPECT_NEAR(sun::solar_position(sun::julian_date(2026, 1, 3, 17), 0, 0).distance_au, 0.98330, 2e-4);
  EXPECT_NEAR(sun::solar_position(sun::julian_date(2026, 7, 6, 18), 0, 0).distance_au, 1.01664, 2e-4);
}

TEST(ClearSky, ZenithSunByHand) {
  // Rigollier et al. (2000) at the zenith: refraction 0.000175 rad, air mass 0.999712, Rayleigh thickness
  // 0.120968, beam transmittance exp(-0.8662 * 3 * m * dR) = 0.730331 for T_LK = 3.
  EXPECT_NEAR(sun::refracted_elevation(kPi / 2) - kPi / 2, 0.00017507, 1e-8);
  const double m = sun::relative_air_mass(kPi / 2);
  EXPECT_NEAR(m, 0.9997121, 1e-6);
  EXPECT_NEAR(sun::rayleigh_thickness(m), 0.1209683, 1e-6);
  EXPECT_NEAR(sun::beam_normal(1000, m, 3), 730.3308, 1e-3);
  EXPECT_NEAR(sun::pressure_ratio(8434.5), std::exp(-1.0), 1e-12);
  // Diffuse at the zenith: g0 T_n (A1 + A2 + A3) with T_LK = 3.
  const double tn = -0.015843 + 0.030543 * 3 + 0.0003797 * 9;
  const double a = (0.26463 - 0.061581 * 3 + 0.0031408 * 9) + (2.04020 + 0.018945 * 3 - 0.011161 * 9) +
                   (-1.3025 + 0.039231 * 3 + 0.0085079 * 9);
  EXPECT_NEAR(sun::diffuse_horizontal(1000, kPi / 2, 3), 1000 * tn * a, 1e-9);
}

TEST(Sun, NoonSunLooksSouthOnANorthUpField) {
  // At 0 E on 21 June the sun crosses the meridian at 12:02 UTC (the equation of time is -1.7 minutes), due
  // south at 90 - 46 + 23.44 = 67.44 degrees from 46 N. A field without a CRS is north-up: +x east, +y
  // south, so the sun's texel azimuth is pi/2 plus its compass azimuth's excess over south.
  HeightField f = truth::procedural(ProceduralKind::fractal, 8, 8, Wrap::clamp);
  const MethodConfig c = sun_config({{"latitude", 46.0},
                                     {"longitude", 0.0},
                                     {"start", "2026-06-21T11:45"},
                                     {"end", "2026-06-21T12:15"},
                                     {"utc_offset", 0},
                                     {"step_minutes", 30}},
                                    f);
  const std::vector<SunStep> steps = sun_steps(c.get<SunConfig>(), scene_of(f));
  ASSERT_EQ(steps.size(), 1u);  // at 12:00 UTC
  EXPECT_NEAR(steps[0].compass_azimuth / kDeg, 179, 1);
  EXPECT_NEAR(steps[0].azimuth / kDeg, 90 + (steps[0].compass_azimuth / kDeg - 180), 1e-9);
  EXPECT_NEAR(steps[0].elevation / kDeg, 67.44, 0.05);
}

// The direct sun against a per-step computation from exact marches: at each step with the sun up, every
// texel is lit when the sun's elevation exceeds its exact horizon at the sun's azimuth. Steps where the two
// are within 2e-5 rad (p1's fast atan is good to about 1e-6) may go either way: the truth brackets them.
void check_against_steps(const HeightField& f, const nlohmann::json& job) {
  const MethodConfig config = sun_config(job, f);
  const SunConfig& c = config.get<SunConfig>();
  const Scene scene = scene_of(f);
  const LayerSet out = config.method->bake(scene, config, RunControl{});
  const Layer& beam = layer(out, "beam");
  const Layer& hours = layer(out, "sun_hours");
  const std::vector<SunStep> steps = sun_steps(c, scene);
  ASSERT_GT(steps.size(), 10u);
  int ties = 0;
  double total = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      const std::size_t t = f.index(i, j);
      double lo = 0, hi = 0, lit_lo = 0, lit_hi = 0;
      for (const SunStep& s : steps) {
        const double h = truth::march_tri(f, i, j, std::cos(s.azimuth), std::sin(s.azimuth), 7);
        const double e = sun_beam(c, s, f.z[t], normal_at(f, i, j).d()) * s.hours;
        if (e <= 0) continue;
        const bool tie = std::abs(s.elevation - h) < 2e-5;
        ties += tie;
        if (s.elevation > h + 2e-5) lo += e, lit_lo += s.hours;
        if (s.elevation > h - 2e-5) hi += e, lit_hi += s.hours;
      }
      total += lo;
      const double v = beam.data[t];
      ASSERT_GE(v, lo * (1 - 1e-4) - 1e-6) << i << ", " << j;
      ASSERT_LE(v, hi * (1 + 1e-4) + 1e-6) << i << ", " << j;
      ASSERT_GE(hours.data[t], lit_lo - 1e-6) << i << ", " << j;
      ASSERT_LE(hours.data[t], lit_hi + 1e-6) << i << ", " << j;
    }
  EXPECT_GT(total, 0);
  EXPECT_LT(ties, f.width * f.height / 100);
}

TEST(Sun, DirectSunMatchesPerStepMarchesOnRoughTerrain) {
  // A day at 46 N in mid-summer, every 20 minutes: shadows from every side on rough terrain.
  const HeightField f = truth::rough_field(40, 36, 50, 0.6, 3, 16);
  check_against_steps(f, {{"latitude", 46.0},
                          {"longitude", 15.0},
                          {"start", "2026-06-21T00:00"},
                          {"end", "2026-06-22T00:00"},
                          {"utc_offset", 2},
                          {"step_minutes", 20},
                          {"layers", {"beam", "sun_hours"}}});
}

TEST(Sun, DirectSunMatchesPerStepMarchesInWinterOnAStep) {
  // Low winter sun at 60 N across a terrace wall: long shadows, grazing incidence.
  const HeightField f = truth::step_field(36, 30, 4, 30);
  check_against_steps(f, {{"latitude", 60.0},
                          {"longitude", -3.0},
                          {"start", "2026-12-21T08:00"},
                          {"end", "2026-12-21T16:00"},
                          {"utc_offset", 0},
                          {"step_minutes", 10},
                          {"layers", {"beam", "sun_hours"}}});
}

TEST(Sun, SkyOnPlanesIsLiuJordan) {
  // An isotropic sky above the horizon seen from a plane of slope beta: (1 + cos beta) / 2 of the
  // horizontal diffuse irradiance (the plane hides exactly the sky below its tangent plane).
  for (double slope : {0.0, 0.3, 1.0}) {
    HeightField f;
    f.width = 24, f.height = 20, f.texel_size = 1;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) f.z.push_back(float(slope * (0.6 * i + 0.8 * j)));
    const nlohmann::json job = {
        {"latitude", 46.0},          {"longitude", 15.0}, {"start", "2026-06-21T04:00"},
        {"end", "2026-06-21T20:00"}, {"utc_offset", 2},   {"step_minutes", 60},
        {"directions", 64},          {"layers", {"sky"}}};
    const MethodConfig config = sun_config(job, f);
    const Scene scene = scene_of(f);
    double diffuse_wh = 0;
    for (const SunStep& s : sun_steps(config.get<SunConfig>(), scene)) diffuse_wh += s.diffuse * s.hours;
    const LayerSet out = config.method->bake(scene, config, RunControl{});
    const double expect = (1 + std::cos(std::atan(slope))) / 2 * diffuse_wh;
    for (float v : layer(out, "sky").data) ASSERT_NEAR(v, expect, 2e-4 * expect) << slope;
  }
}

TEST(Sun, DeterministicForAnyThreadCount) {
  const HeightField f = truth::rough_field(48, 40, 50, 0.6, 7, 16);
  const MethodConfig config = sun_config({{"latitude", 40.0},
                                          {"longitude", 10.0},
                                          {"start", "2026-03-01T06:00"},
                                          {"end", "2026-03-01T18:00"},
                                          {"utc_offset", 1},
                                          {"step_minutes", 30},
                                          {"directions", 8},
                                          {"layers", {"irradiation", "sun_hours"}}},
                                         f);
  const Scene scene = scene_of(f);
  auto run = [&](int threads) {
    LayerSet out;
    tbb::task_arena(threads).execute([&] { out = config.method->bake(scene, config, RunControl{}); });
    return out;
  };
  const LayerSet a = run(1), b = run(2);
  EXPECT_EQ(layer(a, "irradiation").data, layer(b, "irradiation").data);
  EXPECT_EQ(layer(a, "sun_hours").data, layer(b, "sun_hours").data);
}

TEST(Sun, ReaderRefusals) {
  const HeightField f = truth::procedural(ProceduralKind::fractal, 8, 8, Wrap::clamp);
  const nlohmann::json ok = {{"start", "2026-06-21T00:00"}, {"end", "2026-06-22T00:00"}, {"utc_offset", 1}};
  EXPECT_NO_THROW(sun_config(ok, f));
  auto refused = [&](nlohmann::json j) { EXPECT_THROW(sun_config(j, f), InputError) << j.dump(); };
  nlohmann::json j = ok;
  j.erase("utc_offset");
  refused(j);
  j = ok, j["end"] = "2026-06-20T00:00", refused(j);
  j = ok, j["start"] = "2026-02-30T00:00", refused(j);
  j = ok, j["start"] = "2026-06-21 00:00", refused(j);
  j = ok, j["start"] = "2026-06-21T+1:00", refused(j);
  j = ok, j["end"] = "2026-06-22T00:00:60", refused(j);
  j = ok, j["step_minutes"] = 7, refused(j);  // 1440 / 7 is not whole
  j = ok, j["latitude"] = 46.0, refused(j);   // without longitude
  // A field without a CRS needs the place: refused by the reader (validate), naming the entry's latitude,
  // and by the bake of a scene that has none.
  try {
    sun_config(ok, f, /*placed=*/false);
    ADD_FAILURE() << "an unplaced field without latitude was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "/latitude") << e.line();
  }
  j = ok, j["latitude"] = 46.0, j["longitude"] = 7.0;
  EXPECT_NO_THROW(sun_config(j, f, /*placed=*/false));
  const MethodConfig c = sun_config(ok, f);
  EXPECT_THROW(sun_steps(c.get<SunConfig>(), scene_of(f)), InputError);
}

}  // namespace
