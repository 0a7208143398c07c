// p1's far field (job/far_field.hpp, docs/methods/p1.md "Far field"): beyond `beyond` world units from a
// texel, a bound from above on the slope of every point of the surface along the texel's ray, per coarse
// cell of receivers and direction, from the coarse copy of the whole raster (field/coarse_heights.hpp). A
// texel's horizon is the larger of the lane search's exact one over the field's own heights and this
// floor, so a tile of a raster (whose halo holds every point within `beyond`) gets the whole bake's horizons
// bit for bit, and each is at least the exact horizon of the whole surface and at most the certified slack
// above it.
//
// The bound. A receiver p in coarse cell (cx, cy) lies within C/2 texels (each axis) of the cell's centre
// c0, so the point of p's ray at world distance t lies within C/2 of the point r(t) of c0's ray at the same
// distance: inside the 2 x 2 coarse cells around r(t). Walking c0's ray over the dual grid (cells centred
// on the coarse cells' corners, each the highest and the lowest of the four coarse cells it overlaps), a
// dual cell crossed over [ta, tb] with heights in [lo, hi] bounds the slope of every point of every
// receiver's ray there by (hi - z) / (hi >= z ? ta : tb) - c ta (z the receiver's height, c the curvature).
// That is convex in z, so the chord between its values at the cell's lowest and highest height bounds it
// for every receiver height between them: the texel's floor is that chord at its own height. Where every
// receiver's ray stays on the field, the surface there is at least lo, so (lo - z_hi) / (lo <= z_hi ? ta :
// tb) - c tb never exceeds any receiver's exact horizon: the floor's certified lower end, `least`.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "field/coarse_heights.hpp"
#include "field/height_field.hpp"
#include "field/scene.hpp"

namespace hfbake::p1 {

// The coarse copy as the floor walks it, for a field whose texel (0, 0) is the copy's (x0, y0).
struct FloorGrid {
  const CoarseHeights* coarse = nullptr;
  int x0 = 0, y0 = 0;
  double dx = 1, dy = 1;  // the texels' sides, world units
  double beyond = 0;      // world units
  double curvature = 0;   // c: a point at distance d lowered by c d^2
  KeptTexels kept;        // the texels whose slack counts (a tile's interior)
};
// Clamp fields only.
FloorGrid floor_grid(const CoarseHeights& coarse, int x0, int y0, const FieldShape& field, double beyond,
                     double curvature);

// One azimuth's floor for the coarse cells holding a width x height field's texels. Per cell: the bound at
// the cell's lowest and highest height, the certified lower end, and the distance (world units) at which
// the bound at the lowest height is reached; -inf (distance +inf) where no surface lies beyond `beyond`.
struct DirectionFloor {
  int cx0 = 0, cy0 = 0, columns = 0, rows = 0;
  std::vector<float> at_low, at_high, least, distance;
};
// phi: radians from +x towards +y (the world direction (cos phi, sin phi)). Cells in parallel.
void direction_floor(const FloorGrid& grid, int width, int height, double phi, DirectionFloor& out);

struct FloorPick {
  float slope = -std::numeric_limits<float>::infinity();  // the bound at the texel's height
  float least = -std::numeric_limits<float>::infinity();
  float distance = std::numeric_limits<float>::infinity();
};
// Whether a lane search's slope is a caster's on the field: a ray that crosses nothing there gets -inf, or
// from crossings that read the padding beyond the field, a slope near -1e30 (lane_horizons.hpp kOffField).
// Such a texel lies on the field's border facing out: nothing lies beyond `beyond` either, and its floor is
// not taken (the floor of its cell bounds the other receivers' rays, which may run on).
inline bool on_field_caster(float slope) {
  return slope > -1e20f;
}

// The floor of the field's texel (i, j) of height z.
inline FloorPick floor_at(const FloorGrid& grid, const DirectionFloor& f, int i, int j, float z) {
  const CoarseHeights& g = *grid.coarse;
  const int cx = std::min((i + grid.x0) / g.cell, g.columns - 1),
            cy = std::min((j + grid.y0) / g.cell, g.rows - 1);
  const std::size_t at = std::size_t(cy - f.cy0) * std::size_t(f.columns) + std::size_t(cx - f.cx0);
  FloorPick p;
  const float a = f.at_low[at], b = f.at_high[at];
  if (!(a > -std::numeric_limits<float>::infinity())) return p;
  const std::size_t k = g.index(cx, cy);
  const float lo = g.low[k], hi = g.high[k];
  const float w = hi > lo ? std::clamp((z - lo) / (hi - lo), 0.0f, 1.0f) : 0.0f;
  p.slope = a + (b - a) * w;  // the chord
  p.least = f.least[at];
  p.distance = f.distance[at];
  return p;
}

// The lane search's slope m of the field's texel (i, j) of height z, raised to its floor (on_field_caster:
// not a texel facing out of the field); where the floor wins, `distance` (when given) becomes the floor's
// and `slack` the larger of itself and the floor's gap above the texel's certain horizon (only for kept
// texels).
inline float raise_to_floor(const FloorGrid& grid, const DirectionFloor& f, int i, int j, float z, float m,
                            double& slack, float* distance = nullptr) {
  if (!on_field_caster(m)) return m;
  const FloorPick pick = floor_at(grid, f, i, j, z);
  if (!(pick.slope > m)) return m;
  if (grid.kept.contains(i, j)) slack = std::max(slack, double(pick.slope) - std::max(m, pick.least));
  if (distance) *distance = pick.distance;
  return pick.slope;
}

// v rounded up to a float (a bound stays a bound); -inf stays -inf.
float round_up_to_float(double v);

// Bytes one direction's floor holds for a width x height field.
double floor_bytes(int width, int height, int cell);

}  // namespace hfbake::p1
