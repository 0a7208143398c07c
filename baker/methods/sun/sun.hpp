// sun: the sunlight a place receives over a time range, GRASS r.sun's quantities on the exact surface. At
// each time step (the midpoint of each step of the range) the sun's position (solar_position.hpp) gives its
// direction; each texel takes the beam irradiance of the clear-sky model (clear_sky.hpp) times
// cos(incidence) on its normal while the sun is above its exact horizon at the sun's azimuth (a sweep of
// its own per sun position: p1_horizons_at), and the sky's diffuse light is the model's diffuse horizontal
// irradiance times the share of an isotropic sky above the astronomical horizon the texel sees through its
// horizons, at its normal (p1's exact lighting of that sky). Definitions and the comparison with r.sun:
// docs/gis.md, "Sunlight over time".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/far_field.hpp"
#include "methods/method_table.hpp"

namespace hfbake {

struct SunConfig {
  std::optional<double> latitude, longitude;  // degrees; nullopt: the field's centre from its CRS
  double start_jd = 0, end_jd = 0;            // the time range, Julian dates (UT)
  double step_hours = 0.25;
  double linke_turbidity = 3;
  double solar_constant = 1367;  // W/m^2 at 1 astronomical unit
  int directions = 32;           // K of the sky term's horizons
  double near_radius = 2;        // p1's near field (texels)
  std::vector<std::string> layers;
  // p1's far field for the horizons (P1Params::far_field): what lets sun bake in tiles.
  std::optional<FarFieldSpec> far_field;
  std::string file, pointer;  // the entry, for errors found when the scene is known
};

// The entry's settings; `placed`: a CRS places the field on the Earth (MethodContext::placed), else the
// entry must give latitude and longitude.
SunConfig read_sun_config(Params& in, const FieldShape& field, bool placed);

// One time step: the sun's direction in the field's texel frame (x, y texel axes, z up) and what the
// clear-sky model gives at sea level; hours is the step's length.
struct SunStep {
  double elevation = 0, azimuth = 0;  // radians; azimuth from +x towards +y (the texel frame)
  double compass_azimuth = 0;         // radians clockwise from true north
  Vec3 direction;                     // unit, towards the sun, in the texel frame
  double g0 = 0;                      // extraterrestrial irradiance, W/m^2
  double air_mass = 0;                // relative optical air mass at sea level
  double diffuse = 0;                 // diffuse horizontal irradiance, W/m^2
  double hours = 0;
};

// The steps of the range with the sun above the astronomical horizon, for a field whose texel axes point
// east_x (+1: +x is east, -1: west) and north_y (+1: +y is north, -1: south), with true north at grid
// azimuth `convergence` (radians clockwise from the grid's north).
std::vector<SunStep> sun_steps(const SunConfig& c, double latitude, double longitude, double convergence,
                               double east_x, double north_y);
// Where a scene lies and how its texel axes turn: its place from the config or its georeference
// (InputError naming the entry when neither gives one), its axes and north from the geotransform.
struct SunPlace {
  double latitude = 0, longitude = 0;  // degrees
  double convergence = 0;              // radians: true north's azimuth in the grid (clockwise from its north)
  double east_x = 1, north_y = -1;     // +x points east (+1) or west; +y points north (+1) or south
  bool from_crs = false;               // the place came from the field's CRS
};
SunPlace sun_place(const SunConfig& c, const Scene& scene);
// The steps for a scene at its place.
std::vector<SunStep> sun_steps(const SunConfig& c, const Scene& scene);

// Beam irradiance (W/m^2) on a texel at height z (metres above sea level) with normal n at step s, when
// the sun is visible: B0c cos(incidence), 0 when the texel faces away.
double sun_beam(const SunConfig& c, const SunStep& s, double z, const Vec3& n);

LayerSet bake_sun(const Scene& scene, const MethodConfig& config, const RunControl& rc);

MethodInfo sun_method();

}  // namespace hfbake
