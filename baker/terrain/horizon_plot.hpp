// A horizon profile as a polar plot: what hfbake horizon --plot writes.
#pragma once

#include <cstdint>
#include <vector>

#include "terrain/point_horizon.hpp"

namespace hfbake {

// The plot's geometry: a size x size image seen from above, north up and east right, the zenith at the
// centre (cx = cy = size / 2) and elevation e at radius (90° - e) / 90° * horizon_radius, horizon_radius =
// 0.4 size (the 0° circle), so the image's inscribed circle is at e = -22.5°.
struct PolarPlotGeometry {
  int size = 512;
  double horizon_radius() const { return 0.4 * size; }
};

// The horizon's elevation (degrees) at compass azimuth a (degrees), linear between the rays (cyclic); rays
// that found nothing count as -90°.
double profile_elevation(const std::vector<HorizonRay>& rays, double azimuth_deg);

// RGB pixels, rows top first: sky (light blue) above the horizon, terrain (brown) below it, white outside the
// e = -22.5° circle; grey circles at 0°, 30° and 60° and spokes to north, east, south and west.
std::vector<std::uint8_t> horizon_polar_plot(const std::vector<HorizonRay>& rays, const PolarPlotGeometry& g);

}  // namespace hfbake
