// Radius-limited horizons on the triangulated surface (field/triangulation.hpp): the highest and the
// lowest elevation angle under which a texel centre sees the surface along one azimuth, out to a
// horizontal search radius. What the GIS relief quantities (sky-view factor, openness) are made of.
#pragma once

#include "field/coarse_heights.hpp"
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
  // With a far field: up may exceed the exact march's by at most up_slack, down fall below it by at most
  // down_slack (both 0 for the exact march).
  double up_slack = 0, down_slack = 0;
};

// The far field of a march (docs/gis.md, "Far field"): out to `beyond` world units the exact march above;
// from there to the radius the ray walks the cells of `coarse` it crosses (a DDA in the coarse copy's texel
// coordinates), each cell taken at the heights and distances that can only raise the highest elevation and
// only lower the lowest: for a cell crossed over distances [ta, tb] with heights in [lo, hi], up is at
// least (hi - z0) / (hi >= z0 ? ta : tb) - c ta and down at most (lo - z0) / (lo <= z0 ? ta : tb) - c tb.
// So up is never below the exact march's and down never above it. The surface along the ray within a cell
// lies between those two bounds, so the exact up is at least the largest lower bound of a cell (and the
// exact down at most the smallest upper bound): up_slack and down_slack, never more than
// (h + G L) / D + c L (h: the largest height range of a cell crossed; L: a cell's diagonal in world units;
// G: the larger of the exact up + c radius and -down; D = beyond).
struct FarField {
  const CoarseHeights* coarse = nullptr;  // null: the exact march all the way
  double beyond = 0;                      // world units marched exactly
  int x0 = 0, y0 = 0;  // the field's texel (0, 0) in the coarse copy's field (a tile: its window's corner)
};

// radius: world units; curvature: c per world unit (0: flat). clamp fields end at their border (the border
// point is the last one evaluated; with a far field the border of the coarse copy's field); repeat fields
// tile.
HorizonPair radius_horizon(const HeightField& field, int i, int j, double ux, double uy, double radius,
                           double curvature = 0, const FarField& far = {});

}  // namespace hfbake
