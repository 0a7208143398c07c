// Distant lighting in the world frame (+z up): an environment of radiance by direction, and
// directional lights with an angular size. Loading (files, color spaces) lives in env/load_environment.
#pragma once

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
//   width == 2 * height. (How the EXR lat-long / cube / cross conventions map into this: README.)
// levels[0] is full resolution; levels[m] is a 2x box reduction of levels[m - 1] (for filtered lookups).
struct Environment {
  struct Level {
    int width = 0, height = 0;
    std::vector<Rgb> texels;  // row-major
  };

  bool uniform = true;
  Rgb uniform_radiance{1, 1, 1};
  std::vector<Level> levels;

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

}  // namespace hfbake
