// Radius-limited horizons on the triangulated surface (field/triangulation.hpp): the highest and the
// lowest elevation angle under which a texel centre sees the surface along one azimuth, out to a
// horizontal search radius. What the GIS relief quantities (sky-view factor, openness) are made of.
#pragma once

#include "field/height_field.hpp"

namespace hfbake {

// Along the ray from texel (i, j)'s centre in the horizontal direction (dx, dy) (unit, texel axes), the
// surface's height profile is piecewise linear between the ray's crossings of the triangulation's edges
// (texel columns x = n, rows y = n, and the diagonals x + y = n), so the elevation slope (z - z0) / d, a
// ratio of linear functions of d on each piece, takes its extremes at those crossings or at the search
// radius. The march evaluates exactly those points: the result is exact, not sampled.
struct HorizonPair {
  double up = 0, down = 0;  // tangents of the highest and lowest elevation: max and min of (z - z0) / d
  bool any = false;  // false: no surface within the radius (a clamp border right behind); up = down = 0
};

// radius: world units. clamp fields end at their border (the border point is the last one evaluated);
// repeat fields tile.
HorizonPair radius_horizon(const HeightField& field, int i, int j, double dx, double dy, double radius);

}  // namespace hfbake
