// Where a segment in texel coordinates crosses the edges of the triangulated surface
// (field/triangulation.hpp): the columns (x integer), the rows (y integer) and the quads' diagonals (x + y
// integer, the split (i+1, j)-(i, j+1)) -- the kinks of the surface's height along the segment. Read by p1's
// line patterns (far_horizons.cpp LinePattern, and HorizonLineWorker's terrain points), p2's exact line
// profiles and facet segments, lsao's line crossings and terrain/point_horizon's rays. (p1's per-texel search
// walks the same crossings band by band inline, its hot loop; tests/p1 checks it against the exact march.)
#pragma once

#include <utility>

#include "core/vec.hpp"

namespace hfbake {

enum class EdgeFamily { column, row, diagonal };

struct EdgeCrossing {
  double t = 0;  // along the segment, in (0, 1): (x0, y0) + t (x1 - x0, y1 - y0)
  EdgeFamily family = EdgeFamily::column;
  int m = 0;  // the edge: x = m, y = m or x + y = m
};

// At most this many crossings are reported; a segment no longer than a texel along its major axis has at most
// 1 + 1 + 2.
constexpr int kMaxEdgeCrossings = 6;

// The crossings strictly between the ends (an end on an edge is not one), in increasing t (ties keep the
// family order column, row, diagonal). out must hold kMaxEdgeCrossings. Returns their count.
inline int edge_crossings(double x0, double y0, double x1, double y1, EdgeCrossing* out) {
  int n = 0;
  auto family = [&](double a0, double a1, EdgeFamily which) {
    const double d = a1 - a0;
    if (!(d != 0)) return;
    const double lo = d > 0 ? a0 : a1, hi = d > 0 ? a1 : a0;
    for (int c = floor_int(lo) + 1; c < hi && n < kMaxEdgeCrossings; ++c) out[n++] = {(c - a0) / d, which, c};
  };
  family(x0, x1, EdgeFamily::column);
  family(y0, y1, EdgeFamily::row);
  family(x0 + y0, x1 + y1, EdgeFamily::diagonal);
  for (int a = 1; a < n; ++a)  // insertion sort of a handful of values
    for (int b = a; b > 0 && out[b].t < out[b - 1].t; --b) std::swap(out[b], out[b - 1]);
  return n;
}

}  // namespace hfbake
