// Radius-limited horizons on the triangulated surface (field/triangulation.hpp): the highest and the
// lowest elevation angle under which a texel centre sees the surface along one azimuth, out to a
// horizontal search radius. What the GIS relief quantities (sky-view factor, openness) are made of.
#pragma once

#include "field/height_field.hpp"

namespace hfbake {

// Along the ray from texel (i, j)'s centre in the horizontal world direction (ux, uy) (unit; x = columns,
// y = rows), the surface's height z(d) is linear in the horizontal distance d between the ray's crossings
// of the triangulation's edges (texel columns x = n, rows y = n, and the diagonals x + y = n, in texel
// coordinates, so rectangular texels dx x dy change only where along the ray they lie). With the Earth's
// curvature c (Scene::curvature) the elevation's tangent is s(d) = (z(d) - z0) / d - c d. On a piece
// z = a + b d, s is b + (a - z0) / d - c d: monotone when z0 <= a or c = 0, else highest at
// d* = sqrt((z0 - a) / c) and never lowest inside; on the first piece (a = z0) s falls from the facet's
// own slope b at d -> 0. So the extremes lie at the crossings, at the search radius, or (the highest) at d*
// inside a piece or at d -> 0, and the march evaluates exactly those points: the result is exact, not
// sampled.
struct HorizonPair {
  double up = 0, down = 0;  // tangents of the highest and lowest elevation: max and min of s(d)
  bool any = false;  // false: no surface within the radius (a clamp border right behind); up = down = 0
};

// radius: world units; curvature: c per world unit (0: flat). clamp fields end at their border (the border
// point is the last one evaluated); repeat fields tile.
HorizonPair radius_horizon(const HeightField& field, int i, int j, double ux, double uy, double radius,
                           double curvature = 0);

}  // namespace hfbake
