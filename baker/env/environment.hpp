// Distant lighting in the world frame (+z up): an environment of radiance by direction, and
// directional lights with an angular size. Loading (files, color spaces) lives in io/load_environment.hpp;
// how images map to directions: env/env_mapping.hpp.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "core/vec.hpp"

namespace hfbake {

// A distant light such as the sun. `direction` points towards the light (unit). `irradiance` is what it
// delivers, unoccluded, to a surface facing it. Its disk has `angular_diameter` radians (0 = a point).
struct DirectionalLight {
  Vec3 direction{0, 0, 1};
  double angular_diameter = 0;
  Rgb irradiance;
};

// Radiance over the whole sphere of directions, in the world frame, linear RGB, with intensity and
// rotation already applied. Either uniform, or a world-frame lat-long image:
//   row r covers polar angle theta in [pi r / height, pi (r + 1) / height) measured from +z,
//   column c covers azimuth phi in [2 pi c / width, 2 pi (c + 1) / width) measured from +x towards +y,
//   width == 2 * height. (How the EXR lat-long / cube / cross conventions map into this:
//   docs/environment.md.)
// levels[0] is full resolution; levels[m] is a 2x box reduction of levels[m - 1] (for filtered lookups),
// solid-angle weighted. A uniform environment also carries a small constant lat-long (16 x 8), so code that
// integrates texel by texel works for both kinds; `uniform` lets methods take a fast path.
// Texel areas tile the sphere edge to edge: texel_direction(c, r) is the texel's center.
// Build environments with the make_* functions below (or io's load_environment): a default-constructed
// Environment is uniform white with no levels, and setting uniform_radiance by hand does not update the
// stand-in texels.
struct Environment {
  struct Level {
    int width = 0, height = 0;
    std::vector<Rgb> texels;  // row-major
  };

  bool uniform = true;
  Rgb uniform_radiance{1, 1, 1};  // uniform: the radiance; lat-long: its mean over the sphere
  std::vector<Level> levels;

  // Uniform in effect: flagged so, or without a lat-long to look up (the one test of it).
  bool is_uniform() const { return uniform || levels.empty(); }

  // Radiance arriving from direction `dir` (unit, pointing away from the receiver), bilinear.
  Rgb radiance(Vec3 dir) const;
  // Radiance averaged over a cone of half-angle `cone` around `dir` (mip-mapped lookup).
  Rgb radiance_filtered(Vec3 dir, double cone) const;

  // Direction through the center of texel (c, r) of level 0, and that texel's solid angle: for methods
  // that integrate the environment (P1 lighting tables, SH projection, importance sampling).
  Vec3 texel_direction(int c, int r) const;
  double texel_solid_angle(int r) const;
};

Environment make_uniform_environment(Rgb radiance);

// --- building and integrating -----------------------------------------------------------------------

// A world-frame lat-long environment from level-0 texels (width == 2 * height, row-major, rows from the
// zenith down); builds the mip levels.
Environment make_latlong_environment(int width, int height, std::vector<Rgb> texels);

// Rebuilds env.levels[1..] from env.levels[0]: each coarser texel is the solid-angle-weighted mean of its
// 2x2 children, so the integral of radiance over the sphere is the same at every level. Reduction stops
// at 2x1 or when a dimension is odd.
void build_mip_levels(Environment& env);

// Mean radiance over an azimuth wedge, per level-0 row: entry r is the solid-angle mean of row r over
// phi in [phi0, phi1] (radians, from +x towards +y; phi1 > phi0, any range, wrapping around 2 pi; partial
// columns weighted by their overlap). For integrating over azimuthal swaths (P1's lighting tables, Eq. 7)
// without point-sampling one azimuth. A uniform environment gives its radiance for every row.
std::vector<Rgb> azimuth_wedge_profile(const Environment& env, double phi0, double phi1);

// Solid angle of texel row r of a width x height world-frame lat-long (any level).
double latlong_texel_solid_angle(int width, int height, int r);

// Integral of radiance over the whole sphere (W/m^2 sr * sr) at mip level `level`; for a uniform
// environment 4 pi times its radiance.
Rgb integrate_sphere(const Environment& env, int level = 0);

// --- the built-in procedural sky --------------------------------------------------------------------

// A clear-sky gradient plus a sun. Radiance at elevation e above the horizon (z = sin e):
//   L(e) = horizon + (zenith - horizon) * sin(e)       (linear in z, so every lat-long texel stores its
//                                                         exact mean and closed forms exist for tests)
// and `ground` everywhere below the horizon (the terrain beyond the height field's border, lit grey).
// The sun is not rasterised: it is returned as a DirectionalLight (direction from elevation and azimuth,
// azimuth from +x towards +y, angular size, irradiance). A sun at or below the horizon (elevation <= 0)
// is behind the ground and gives no light; zero irradiance means no sun.
struct SkySpec {
  Rgb zenith{0.25f, 0.45f, 0.9f};
  Rgb horizon{0.8f, 0.85f, 0.95f};
  Rgb ground{0.2f, 0.18f, 0.15f};
  double sun_elevation_deg = 35;
  double sun_azimuth_deg = 135;
  double sun_angular_diameter_deg = 0.53;
  Rgb sun_irradiance{3.0f, 2.9f, 2.7f};
  float intensity = 1;      // multiplies sky and sun
  double rotation_deg = 0;  // turns sky and sun about +z (adds to the sun's azimuth)
  int height = 64;          // lat-long rows (width = 2 * height); the gradient is smooth
};

// An environment with the lights that belong to it (the sky's sun).
struct EnvironmentLighting {
  Environment environment;
  std::vector<DirectionalLight> lights;
};

EnvironmentLighting make_sky_environment(const SkySpec& spec);

// Unit direction towards a light at elevation / azimuth (degrees; azimuth from +x towards +y).
Vec3 direction_from_elevation_azimuth(double elevation_deg, double azimuth_deg);

// --- the cube-map view (P1's lighting tables) -------------------------------------------------------

// Six square faces in the world frame, in the order +x, -x, +y, -y, +z, -z. Face f maps texel (i, j)
// (i = column, j = row, both 0..size-1) to the direction
//   normalize(axis_f + a * u_f + b * v_f),  a = 2 (i + 0.5) / size - 1,  b = 2 (j + 0.5) / size - 1
// with (axis, u, v) = (+x, +y, +z), (-x, -y, +z), (+y, -x, +z), (-y, +x, +z), (+z, +x, +y), (-z, +x, -y)
// (u x v = axis for every face). Each texel stores the mean radiance over its solid angle.
struct CubeView {
  int size = 0;
  std::array<std::vector<Rgb>, 6> faces;  // size * size texels each, row-major (j * size + i)

  static Vec3 face_axis(int face);
  static Vec3 face_u(int face);
  static Vec3 face_v(int face);
  Vec3 texel_direction(int face, int i, int j) const;
  double texel_solid_angle(int i, int j) const;  // the same on every face; sums to 4 pi over all texels
  const Rgb& at(int face, int i, int j) const { return faces[face][std::size_t(j) * size + i]; }
};

CubeView make_cube_view(const Environment& env, int size);

}  // namespace hfbake
