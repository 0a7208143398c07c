// The horizon profile of one point of a height field: for each compass azimuth, the highest elevation
// under which an observer above the point sees the triangulated surface (field/triangulation.hpp), the
// caster's distance and position. What GIS tools call a point horizon (GRASS r.horizon's point mode).
#pragma once

#include <optional>
#include <vector>

#include "field/height_field.hpp"
#include "terrain/earth.hpp"

namespace hfbake {

// How texel axes map to the ground at the point: world units east per +1 column and north per +1 row
// (signed; a north-up projected raster with pixel size t has {t, -t}). Texels need not be square (a
// geographic raster's are not).
struct GroundFrame {
  double east_per_x = 1, north_per_y = -1;
  // The grid's azimuth of true north at the point (radians, clockwise from the grid's north: a projection's
  // meridian convergence); the ray reported at compass azimuth A walks the grid towards A + convergence.
  double convergence = 0;
};

struct PointHorizonQuery {
  double x = 0, y = 0;         // texel coordinates (x = i at texel centres), on the surface
  double observer_height = 0;  // world units above the surface at (x, y)
  int directions = 360;        // K compass azimuths 360° k / K, k = 0 north, clockwise
  GroundFrame frame;
  std::optional<EarthCurvature> curvature;  // none: a flat Earth
};

struct HorizonRay {
  double azimuth_deg = 0;      // compass, clockwise from north
  bool found = false;          // false: no surface in that direction (the point is on the border)
  double elevation_deg = 0;    // above the horizontal plane of the observer, curvature included
  double distance = 0;         // horizontal distance to the caster, world units
  double x = 0, y = 0, z = 0;  // the caster: texel coordinates and its height on the surface (uncorrected)
};

// The surface's height at (x, y) (texel coordinates); nullopt outside the texel centres' rectangle
// [0, w-1] x [0, h-1] or where a corner of the point's facet is not finite (NoData).
std::optional<double> surface_height(const HeightField& field, double x, double y);

// One ray per azimuth from (x, y) across the clamp field to its border. Along a ray the surface is linear
// between its crossings of texel columns, rows and diagonals; the elevation of a point at horizontal
// distance d is atan((z(d) - c d^2 - z0) / d) with c the curvature coefficient (0 on a flat Earth), whose
// maxima lie at those crossings, at the border, or (c > 0) where the slope's derivative vanishes inside a
// piece, d* = sqrt((z0 - a) / c) for the piece's line z = a + b d, or (an eye on the surface, c > 0) as
// d -> 0 on the first piece, where the facet's own slope b casts (distance 0): all of them are evaluated, so
// the result is exact on the surface. Pieces touching a non-finite height are holes: nothing casts there (an
// edge's points take their height from the edge's two vertices, so the last edge before a hole casts). A
// crossing within 1e-6 texel of the eye is its own edge, not a caster (its rise is rounding). The
// point must have a surface_height.
std::vector<HorizonRay> point_horizon(const HeightField& field, const PointHorizonQuery& query);

}  // namespace hfbake
